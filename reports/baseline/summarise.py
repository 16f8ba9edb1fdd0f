"""Summarise a ledger holding SUMO's own driver (controller ``sumo``) beside the plug-in's runs: per
scenario over its seeds, the baseline's goals, collisions, rule violations and road use, its median time
to goal, and the other controller's median time and median travel_time_ratio against it.

Usage: python reports/baseline/summarise.py LEDGER.sqlite > table.md
"""
import sqlite3
import sys

import pandas as pd

from sumo_avoid.studies.baseline import BASELINE, with_travel_time_ratio


def _median(s: pd.Series) -> str:
    s = s.dropna().astype(float)
    return f"{s.median():.1f}" if len(s) else "-"


def _row(name: str, g: pd.DataFrame) -> str:
    b = g[g["controller"] == BASELINE]
    other = g[g["controller"] != BASELINE]
    ratio = other["travel_time_ratio"].dropna()
    n = lambda c, d=b: int(d[c].fillna(0).sum())  # noqa: E731
    ctl = ",".join(sorted(set(other["controller"]))) or "-"
    return (f"| {name} | {len(b)} | {n('goal_reached')}/{len(b)} | {n('collisions')} / {n('sumo_ego_collisions')} "
            f"| {n('red_light_violations')} / {n('yield_violations')} / {n('stop_sign_violations')} / "
            f"{n('crossing_violations')} | {b['forbidden_lane_m'].sum():.1f} / {b['wrong_way_m'].sum():.1f} / "
            f"{b['off_road_m'].sum():.1f} | {b['phi_wall'].max():.2f} | {_median(b['time_to_goal_s'])} "
            f"| {ctl} | {n('goal_reached', other)}/{len(other)} | {_median(other['time_to_goal_s'])} "
            f"| {f'{ratio.median():.2f} ({len(ratio)})' if len(ratio) else '-'} |")


def main(path: str) -> None:
    con = sqlite3.connect(path)
    df = with_travel_time_ratio(pd.read_sql("select * from runs where status = 'done'", con))
    con.close()
    print("| scenario | runs | SUMO's driver: goal | collisions (ours / SUMO's with the ego) "
          "| red light / yield / stop sign / crossing violations | forbidden_lane_m / wrong_way_m / off_road_m "
          "| max phi_wall, m | median time to goal, s | plug-in | its goal | its median time to goal, s "
          "| its median travel_time_ratio (runs with one) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, g in df.groupby("scenario", sort=False):
        print(_row(name, g))


if __name__ == "__main__":
    main(sys.argv[1])
