"""The README's table of SUMO's own driver beside APF-SA: one row per suite (and sensor), from per-run CSVs that hold a
travel_time_ratio column (reports/baseline/runs_*.csv, reports/cities/runs_*.csv).

Usage: python reports/cities/readme_rows.py "NAME=FILE.csv[,FILE2.csv]" ...

SUMO's driver: its goals, collisions (ours / SUMO's with the ego; persons), red-light / yield / stop-sign / crossing
violations and road use, summed over its runs. APF-SA: its goals and its median travel_time_ratio over the runs with
one (its time to goal over SUMO's driver's on the same scenario and seed), per sensor.
"""
import sys

import pandas as pd

HEAD = ("| suite | SUMO's driver: runs | goal | collisions (ours / SUMO's with the ego) | vru_collisions "
        "| red light / yield / stop sign / crossing | off_road_m / forbidden_lane_m / wrong_way_m "
        "| APF-SA: sensor | goal | median travel_time_ratio (runs with one) |")


def _n(g: pd.DataFrame, col: str) -> int:
    return int(pd.to_numeric(g[col], errors="coerce").fillna(0).sum())


def rows(name: str, df: pd.DataFrame) -> list[str]:
    df = df[df["status"] == "done"]
    base = df[df["controller"] == "sumo"]
    viol = " / ".join(str(_n(base, c)) for c in ("red_light_violations", "yield_violations", "stop_sign_violations",
                                                  "crossing_violations"))
    road = " / ".join(f"{base[c].sum():.1f}" for c in ("off_road_m", "forbidden_lane_m", "wrong_way_m"))
    left = (f"| {name} | {len(base)} | {_n(base, 'goal_reached')}/{len(base)} | {_n(base, 'collisions')} / "
            f"{_n(base, 'sumo_ego_collisions')} | {_n(base, 'vru_collisions')} | {viol} | {road} ")
    out = []
    apf = df[df["controller"] == "apf_sa"]
    for sensor, g in apf.groupby("sensor", sort=True):
        r = g["travel_time_ratio"].dropna()
        med = f"{r.median():.2f} ({len(r)})" if len(r) else "- (0)"
        out.append(f"{left}| {sensor} | {_n(g, 'goal_reached')}/{len(g)} | {med} |")
    return out or [f"{left}| - | - | - |"]


def main(argv: list[str]) -> int:
    if not argv or not all("=" in a for a in argv):
        print('usage: python reports/cities/readme_rows.py "NAME=FILE.csv[,FILE2.csv]" ...', file=sys.stderr)
        return 2
    suites = []
    for arg in argv:  # every file read before anything is printed
        name, files = arg.split("=", 1)
        suites.append((name, pd.concat([pd.read_csv(f) for f in files.split(",")], ignore_index=True)))
    print(HEAD)
    print("|" + "---|" * (HEAD.count("|") - 1))
    for name, df in suites:
        for line in rows(name, df):
            print(line)
    return 0


if __name__ == "__main__":
    from one_line import run

    run(main)
