"""Summarise a streets-suite ledger: per scenario over its seeds, the issue-33 acceptance metrics.

Usage: python reports/streets/summarise.py LEDGER.sqlite > table.md
"""
import sqlite3
import sys

import pandas as pd


def _row(name: str, g: pd.DataFrame) -> str:
    gap = g["min_gap_vru_m"].dropna()
    seeds = ",".join(map(str, sorted(g["seed"])))
    return (f"| {name} | {seeds} | {int(g['goal_reached'].sum())}/{len(g)} "
            f"| {int(g['collisions'].sum())} / {int(g['sumo_ego_collisions'].sum())} | {int(g['vru_collisions'].sum())} "
            f"| {int(g['crossing_violations'].sum())} | {int(g['red_light_violations'].sum())} / "
            f"{int(g['yield_violations'].sum())} | {g['forbidden_lane_m'].sum():.1f} | {g['off_road_m'].sum():.1f} "
            f"| {g['wrong_way_m'].sum():.1f} | {g['phi_wall'].max():.2f} | {f'{gap.min():.2f}' if len(gap) else '-'} |")


def main(path: str) -> None:
    con = sqlite3.connect(path)
    df = pd.read_sql("select * from runs", con)
    con.close()
    print("| scenario | seeds | goal | collisions (ours / SUMO's with the ego) | vru_collisions | crossing_violations "
          "| red light / yield | forbidden_lane_m | off_road_m | wrong_way_m | max phi_wall, m | min gap to a VRU, m |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, g in df.groupby("scenario", sort=False):
        print(_row(name, g))


if __name__ == "__main__":
    main(sys.argv[1])
