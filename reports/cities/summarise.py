"""Summarise a city-suite ledger (scenarios/cities.toml): per scenario, controller and sensor over the seeds, the
acceptance metrics of issue 34 item 4 with travel_time_ratio against SUMO's own driver on the same scenario and
seed (sumo_avoid.studies.baseline), then the totals per controller and sensor.

Usage: python reports/cities/summarise.py LEDGER.sqlite [--csv RUNS.csv] > table.md
"""
import sys

import pandas as pd

from sumo_avoid.studies import ledger
from sumo_avoid.studies.baseline import BASELINE, with_travel_time_ratio

RUN_COLUMNS = ["scenario", "controller", "sensor", "seed", "status", "goal_reached", "time_to_goal_s", "travel_time_ratio",
               "collisions", "sumo_ego_collisions", "vru_collisions", "collisions_ego_stopped", "collisions_other_jumped",
               "max_impact_speed_mps", "red_light_violations", "yield_violations",
               "stop_sign_violations", "crossing_violations", "off_road_m", "forbidden_lane_m", "wrong_way_m", "speeding_m",
               "phi_wall", "min_gap_m", "min_gap_vru_m", "sumo_collisions", "sim_time_s", "wall_s", "code", "error"]
HEAD = ("| scenario | controller | sensor | seeds | goal | collisions (ours / SUMO's with the ego) | vru_collisions "
        "| red light / yield / stop sign / crossing | off_road_m | forbidden_lane_m / wrong_way_m | speeding_m "
        "| max phi_wall, m "
        "| median time to goal, s | median travel_time_ratio (runs with one) |")


def runs(path: str) -> pd.DataFrame:
    df = ledger.read(path)
    df = with_travel_time_ratio(df)
    df["sensor"] = [("-" if c == BASELINE else s) for c, s in zip(df["controller"], df["sensor"])]
    return df[[c for c in RUN_COLUMNS if c in df]].sort_values(["scenario", "controller", "sensor", "seed"])


def _n(g: pd.DataFrame, col: str) -> int:
    return int(g[col].fillna(0).sum())


def _median(s: pd.Series, fmt: str) -> str:
    s = s.dropna().astype(float)
    return fmt.format(s.median()) if len(s) else "-"


def row(name: str, g: pd.DataFrame) -> str:
    failed = int((g["status"] != "done").sum())
    d = g[g["status"] == "done"]
    seeds = ",".join(map(str, sorted(g["seed"]))) + (f" ({failed} failed)" if failed else "")
    viol = " / ".join(str(_n(d, c)) for c in ("red_light_violations", "yield_violations", "stop_sign_violations",
                                               "crossing_violations"))
    ratio = d["travel_time_ratio"]
    return (f"| {name} | {seeds} | {_n(d, 'goal_reached')}/{len(g)} | {_n(d, 'collisions')} / "
            f"{_n(d, 'sumo_ego_collisions')} | {_n(d, 'vru_collisions')} | {viol} | {d['off_road_m'].sum():.1f} "
            f"| {d['forbidden_lane_m'].sum():.1f} / {d['wrong_way_m'].sum():.1f} | "
            f"{(format(d['speeding_m'].sum(), '.1f') if 'speeding_m' in d else '-')} | "
            f"{d['phi_wall'].max():.2f} | {_median(d['time_to_goal_s'], '{:.1f}')} "
            f"| {_median(ratio, '{:.2f}')} ({int(ratio.notna().sum())}) |")


def main(argv: list[str]) -> int:
    if len(argv) not in (1, 3) or (len(argv) == 3 and argv[1] != "--csv"):
        print("usage: python reports/cities/summarise.py LEDGER.sqlite [--csv RUNS.csv]", file=sys.stderr)
        return 2
    df = runs(argv[0])
    if len(argv) == 3:
        df.to_csv(argv[2], index=False)
    print(HEAD)
    print("|" + "---|" * (HEAD.count("|") - 1))
    for (scn, ctrl, sensor), g in df.groupby(["scenario", "controller", "sensor"], sort=True):
        print(row(f"{scn} | {ctrl} | {sensor}", g))
    print()
    print(HEAD.replace("| scenario | controller | sensor | seeds |", "| all scenarios | controller | sensor | runs |"))
    print("|" + "---|" * (HEAD.count("|") - 1))
    for (ctrl, sensor), g in df.groupby(["controller", "sensor"], sort=True):
        line = row(f"all | {ctrl} | {sensor}", g)
        cells = line.split(" | ")
        cells[3] = str(len(g))  # the runs, not the seed list
        print(" | ".join(cells))
    return 0


if __name__ == "__main__":
    from one_line import run

    run(main)
