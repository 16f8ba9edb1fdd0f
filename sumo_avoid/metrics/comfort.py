"""Ride comfort of the egos from the recording: the largest longitudinal jerk and lateral
acceleration, per ego, max over egos (finite differences on the recorded steps, at their own times).

Per ego, rows k = 0..n-1 sorted by step, at times t_k (s), centres p_k (m), headings h_k (rad),
recorded speeds s_k (m/s); an interval is two consecutive rows of the same ego with t_{k+1} > t_k.

* Longitudinal speed on interval k: v_{k+1/2} = (p_{k+1} - p_k) · ū / (t_{k+1} - t_k), ū the unit
  mean of the two headings: the displacement along the car, signed (backwards < 0). Positions, not
  the ``speed`` column: SUMO reports a reversing ego's speed as positive, and |v| through
  a reversal would look like a jerk spike.
* Acceleration at row k: a_k = (v_{k+1/2} - v_{k-1/2}) / ((t_{k+1} - t_{k-1}) / 2).
* Jerk on interval k: j_{k+1/2} = (a_{k+1} - a_k) / (t_{k+1} - t_k); at a constant step dt this is
  the third difference of the position along the car over dt³ (four consecutive rows).
* Yaw rate at row k: ω_k = wrap(h_{k+1} - h_{k-1}) / (t_{k+1} - t_{k-1}) (central difference, the
  heading change wrapped into (-π, π], so crossing ±π is no jump); lateral acceleration
  |s_k ω_k|.

These are step-level values: an acceleration that jumps by Δa within one step shows as a jerk of
Δa / step_s, so jerks compare between runs at the same ``step_s`` (in metrics.json). None when no
ego has enough rows (four for the jerk, three for the lateral acceleration).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.ego_rows import EgoRows
from sumo_avoid.metrics.standard import ego_rows
from sumo_avoid.rollout.result import RunResult


def _wrap(a):
    return np.pi - np.mod(np.pi - a, 2.0 * np.pi)  # into (-pi, pi]


def comfort(traj: pd.DataFrame, egos: EgoRows | None = None) -> dict:
    """``max_abs_jerk_mps3`` and ``max_lat_accel_mps2`` over the egos of a trajectory table
    (``egos``: its :class:`EgoRows`, if already made)."""
    egos = EgoRows.of(traj) if egos is None else egos
    e = egos.table
    none = {"max_abs_jerk_mps3": None, "max_lat_accel_mps2": None}
    if len(e) < 3:
        return none
    o = egos.by_id()
    code = egos.code[o]
    t = e["time_s"].to_numpy(float)[o]
    x, y = e["x"].to_numpy(float)[o], e["y"].to_numpy(float)[o]
    h, s = e["heading"].to_numpy(float)[o], e["speed"].to_numpy(float)[o]
    dt = np.diff(t)
    ok = (code[1:] == code[:-1]) & (dt > 0)  # interval k: rows k, k+1
    ux, uy = np.cos(h[:-1]) + np.cos(h[1:]), np.sin(h[:-1]) + np.sin(h[1:])
    norm = np.hypot(ux, uy)
    flip = norm < 1e-9  # headings opposite: take the first one's
    safe = np.where(flip, 1.0, norm)
    ux = np.where(flip, np.cos(h[:-1]), ux / safe)
    uy = np.where(flip, np.sin(h[:-1]), uy / safe)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = (np.diff(x) * ux + np.diff(y) * uy) / dt  # (n-1,) on the intervals
        a_ok = ok[:-1] & ok[1:]  # row k = 1..n-2
        span = t[2:] - t[:-2]
        a = (v[1:] - v[:-1]) / (span / 2.0)
        j_ok = a_ok[:-1] & a_ok[1:]  # interval k = 1..n-3
        j = (a[1:] - a[:-1]) / dt[1:-1]
        lat = np.abs(s[1:-1] * _wrap(h[2:] - h[:-2]) / span)
    out = dict(none)
    if j_ok.any():
        out["max_abs_jerk_mps3"] = float(np.abs(j[j_ok]).max())
    if a_ok.any():
        out["max_lat_accel_mps2"] = float(lat[a_ok].max())
    return out


class Comfort(Metric):
    """Largest longitudinal jerk and lateral acceleration of any ego (per ego, max over egos)."""

    keys = Keys(("max_abs_jerk_mps3", "max_lat_accel_mps2"))

    def compute(self, run: RunResult) -> dict:
        return comfort(run.traj, ego_rows(run))
