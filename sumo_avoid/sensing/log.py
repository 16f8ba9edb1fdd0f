"""The per-scan radar log as a table (``detections.csv`` when ``radar.log_detections = true``)."""
from __future__ import annotations

import numpy as np
import pandas as pd

COLUMNS = ["time_s", "ego", "mount", "range_m", "azimuth_rad", "radial_speed_mps", "x", "y", "target", "vru"]


def detections_table(scans) -> pd.DataFrame:
    """One row per detection of every logged scan; x, y in net coordinates; target '' = false alarm;
    vru: the radar labelled the return a person or cyclist."""
    frames = []
    for d in sorted(scans, key=lambda d: d.time_s):  # stable: front before rear at one time
        if d.n == 0:
            continue
        xy = d.points()
        frames.append(pd.DataFrame({
            "time_s": np.full(d.n, d.time_s), "ego": [d.ego_ids[e] for e in d.ego],
            "mount": d.mount, "range_m": d.range_m,
            "azimuth_rad": d.azimuth_rad, "radial_speed_mps": d.radial_speed_mps, "x": xy[:, 0], "y": xy[:, 1],
            "target": list(d.target), "vru": d.vru_mask()}))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=COLUMNS)
