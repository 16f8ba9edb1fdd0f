"""Summarise a ledger holding SUMO's own driver (controller ``sumo``) beside the plug-in's runs: per
scenario over its seeds, the baseline's goals, collisions, rule violations and road use, its median time
to goal, and the other controller's goals, median time and median travel_time_ratio against it.

Usage: python reports/baseline/summarise.py LEDGER.sqlite > table.md
"""
import sys

import pandas as pd

from sumo_avoid.studies import ledger
from sumo_avoid.studies.baseline import BASELINE, with_travel_time_ratio
from sumo_avoid.studies.report import markdown

COLUMNS = {  # column -> (rows: baseline or plug-in, how a group of runs becomes the cell)
    "runs": ("sumo", len),
    "SUMO's driver: goal": ("sumo", lambda g: _goals(g)),
    "collisions (ours / SUMO's with the ego)": ("sumo", lambda g: f"{_sum(g, 'collisions')} / {_sum(g, 'sumo_ego_collisions')}"),
    "red light / yield / stop sign / crossing violations": (
        "sumo", lambda g: " / ".join(str(_sum(g, c)) for c in ("red_light_violations", "yield_violations",
                                                               "stop_sign_violations", "crossing_violations"))),
    "forbidden_lane_m / wrong_way_m / off_road_m": (
        "sumo", lambda g: " / ".join(f"{g[c].sum():.1f}" for c in ("forbidden_lane_m", "wrong_way_m", "off_road_m"))),
    "max phi_wall, m": ("sumo", lambda g: f"{g['phi_wall'].max():.2f}"),
    "median time to goal, s": ("sumo", lambda g: _median(g["time_to_goal_s"], "{:.1f}")),
    "plug-in": ("other", lambda g: ",".join(sorted(set(g["controller"]))) or "-"),
    "its goal": ("other", lambda g: _goals(g)),
    "its median time to goal, s": ("other", lambda g: _median(g["time_to_goal_s"], "{:.1f}")),
    "its median travel_time_ratio (runs with one)": (
        "other", lambda g: _median(g["travel_time_ratio"], "{:.2f}") + f" ({g['travel_time_ratio'].notna().sum()})"),
}


def _sum(g: pd.DataFrame, col: str) -> int:
    return int(g[col].fillna(0).sum())


def _goals(g: pd.DataFrame) -> str:
    """Runs that reached their goal of those run; n/a where no run has one (a flock)."""
    return "n/a" if g["goal_reached"].isna().all() else f"{_sum(g, 'goal_reached')}/{len(g)}"


def _median(s: pd.Series, fmt: str) -> str:
    s = s.dropna().astype(float)
    return fmt.format(s.median()) if len(s) else "-"


def table(df: pd.DataFrame) -> pd.DataFrame:
    df = with_travel_time_ratio(df[df["status"] == "done"])
    rows = []
    for name, g in df.groupby("scenario", sort=False):
        part = {"sumo": g[g["controller"] == BASELINE], "other": g[g["controller"] != BASELINE]}
        rows.append({"scenario": name, **{c: cell(part[which]) for c, (which, cell) in COLUMNS.items()}})
    return pd.DataFrame(rows)


if __name__ == "__main__":
    t = table(ledger.read(sys.argv[1]))
    print(markdown(t, list(t.columns)), end="")
