"""Per-step series of a run for the time-series plot: smallest ego gap and mean ego speed."""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid.core.geometry import footprint_corners, pairwise_footprint_distance
from sumo_avoid.rollout.result import RunResult


def series(res: RunResult) -> pd.DataFrame:
    """Per step: smallest ego-to-other footprint gap and the mean ego speed (for plots)."""
    rows = []
    for step, g in res.traj.groupby("step", sort=True):
        ego = g["is_ego"].to_numpy()
        if not ego.any():
            continue
        c = footprint_corners(g[["x", "y"]].to_numpy(), g["heading"].to_numpy(), g["length"].to_numpy(),
                              g["width"].to_numpy())
        gap = np.nan
        if len(g) > 1:
            d = pairwise_footprint_distance(c[ego], c)
            d[np.arange(ego.sum()), np.flatnonzero(ego)] = np.inf
            gap = float(d.min())
        rows.append((float(g["time_s"].iloc[0]), gap, float(g.loc[ego, "speed"].mean())))
    return pd.DataFrame(rows, columns=["time_s", "min_gap_m", "ego_speed_mps"])
