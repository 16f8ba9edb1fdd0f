"""Per-step recording of the world into arrays; becomes one pandas table after the run.

Egos are always recorded; other vehicles only within ``record_radius_m`` of an ego (0 = all), to
keep big-traffic runs small. SUMO's own collision reports are kept beside, one event per pair and
contact episode (consecutive steps), the same rule as the plug-in's own events.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from .snapshot import Snapshot

COLUMNS = ["step", "time_s", "id", "is_ego", "x", "y", "vx", "vy", "speed", "heading", "length", "width"]


def near_any(points: np.ndarray, centres: np.ndarray, radius_m: float) -> np.ndarray:
    """(N,) bool: which ``points`` (N, 2) lie within ``radius_m`` of any of ``centres`` (M, 2).

    First each point is tried against the centres just before and after it along the axis the
    centres spread most on (usually enough when they are spread along a road); only the points
    this does not settle go to a k-d tree over all centres. Same distances (sqrt(dx^2 + dy^2)) and
    the same test as the k-d tree alone, so the same answer."""
    N, M = len(points), len(centres)
    if N == 0 or M == 0:
        return np.zeros(N, bool)
    ax = int(np.ptp(centres[:, 1]) > np.ptp(centres[:, 0]))
    order = np.argsort(centres[:, ax], kind="stable")
    i = np.searchsorted(centres[order, ax], points[:, ax])
    near = np.zeros(N, bool)
    for j in (np.maximum(i - 1, 0), np.minimum(i, M - 1)):
        d = points - centres[order[j]]
        near |= np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) <= radius_m
    rest = np.flatnonzero(~near)
    if len(rest):
        dist, _ = cKDTree(centres).query(points[rest], k=1, distance_upper_bound=radius_m * (1 + 1e-9))
        near[rest] = dist <= radius_m
    return near


class Recorder:
    def __init__(self, record_radius_m: float = 0.0):
        self.radius = record_radius_m
        self._chunks: list[tuple] = []
        self._sumo_events: list[dict] = []
        self._sumo_last: dict[tuple[str, str], int] = {}

    def record(self, step: int, snap: Snapshot) -> None:
        if snap.n == 0:
            return
        keep = snap.is_ego.copy()
        if self.radius > 0 and keep.any():
            keep |= near_any(snap.pos, snap.pos[snap.is_ego], self.radius)
        elif self.radius <= 0:
            keep[:] = True
        idx = np.flatnonzero(keep)
        if len(idx) == 0:
            return
        ids = np.array(snap.ids, dtype=object)[idx]
        self._chunks.append((step, snap.time_s, ids, snap.is_ego[idx], snap.pos[idx], snap.vel[idx],
                             snap.heading[idx], snap.length[idx], snap.width[idx]))

    def record_sumo_collisions(self, step: int, collisions) -> None:
        for c in collisions:
            pair = tuple(sorted((c.collider, c.victim)))
            if self._sumo_last.get(pair) != step - 1 and self._sumo_last.get(pair) != step:
                self._sumo_events.append({"step": step, "time_s": c.time_s, "a": pair[0], "b": pair[1],
                                          "collider": c.collider, "victim": c.victim, "type": c.kind,
                                          "lane": c.lane})
            self._sumo_last[pair] = step

    def table(self) -> pd.DataFrame:
        if not self._chunks:
            return pd.DataFrame({c: pd.Series(dtype=float) for c in COLUMNS})
        sizes = [len(c[2]) for c in self._chunks]
        pos = np.concatenate([c[4] for c in self._chunks])
        vel = np.concatenate([c[5] for c in self._chunks])
        return pd.DataFrame({
            "step": np.repeat([c[0] for c in self._chunks], sizes).astype(np.int64),
            "time_s": np.repeat([c[1] for c in self._chunks], sizes),
            "id": np.concatenate([c[2] for c in self._chunks]).astype(str),
            "is_ego": np.concatenate([c[3] for c in self._chunks]),
            "x": pos[:, 0], "y": pos[:, 1], "vx": vel[:, 0], "vy": vel[:, 1],
            "speed": np.hypot(vel[:, 0], vel[:, 1]),
            "heading": np.concatenate([c[6] for c in self._chunks]),
            "length": np.concatenate([c[7] for c in self._chunks]),
            "width": np.concatenate([c[8] for c in self._chunks]),
        })

    def sumo_events(self) -> pd.DataFrame:
        return pd.DataFrame(self._sumo_events, columns=["step", "time_s", "a", "b", "collider", "victim", "type", "lane"])
