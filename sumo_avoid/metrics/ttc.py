"""The plug-in's own 2-D time-to-collision from footprints (``min_ttc2d_s``), on or off the lanes.

At each recorded step, for each ego i and each other vehicle j present (ego or not), both are
taken to keep their recorded velocity (vx, vy) and heading; TTC is the first time t in
[0, horizon] at which their oriented rectangles (centre, heading, length x width) touch:

    for every axis n among the four edge normals of the two rectangles (separating-axis theorem),
    the projections overlap while |d_n + w_n t| <= R_n, with d_n = (c_j - c_i)·n, w_n = (v_j - v_i)·n
    and R_n = the sum of the two half-extents on n (L/2 |u·n| + W/2 |u⊥·n| each); that is the
    interval [min, max] of (±R_n - d_n) / w_n (all t if w_n = 0 and |d_n| <= R_n, none otherwise).
    TTC = max(0, latest entry) if that is <= the earliest exit and <= horizon, else none.

0 when the footprints already touch. ``min_ttc2d_s`` is the smallest over the run, clamped at the
horizon (:attr:`TTC2D.horizon_s`, 10 s; = 10 when no contact is predicted within 10 s), None when
the run has no ego. The pairs come from the k-d tree search of :mod:`sumo_avoid.metrics.pairs`
within a radius r, grown until it cannot miss the minimum: a pair farther apart than r (centres)
has a gap > r - 2 × the largest half diagonal and closes at most at 2 × the largest recorded
speed, so r >= 2 hd_max + 2 v_max × (smallest TTC found) suffices.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.pairs import Rows
from sumo_avoid.metrics.standard import pair_rows, recorded, road_apart
from sumo_avoid.rollout.result import RunResult

CHUNK = 200_000  # pairs per vectorised batch (memory)


@dataclass(frozen=True)
class TTC2D:
    horizon_s: float = 10.0  # look-ahead of the constant-velocity prediction, s
    touch_m: float = 1e-9  # rectangles this close count as touching (the collision test's tolerance), m


def _axes(h):
    c, s = np.cos(h), np.sin(h)
    return np.stack([c, s], -1), np.stack([-s, c], -1)


def _dot(a, b):
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]


def ttc_rectangles(ca, ha, la, wa, va, cb, hb, lb, wb, vb, horizon_s: float, touch_m: float = 1e-9) -> np.ndarray:
    """Time (s) until rectangles a and b, moving at constant velocities without turning, first
    touch; inf if not within ``horizon_s``. Centres ``c`` and velocities ``v`` (N,2) m, m/s; headings
    ``h`` rad; lengths ``l`` and widths ``w`` m; all (N,) or broadcastable. Vectorised over N."""
    ca, va, cb, vb = (np.asarray(z, float).reshape(-1, 2) for z in (ca, va, cb, vb))
    ha, la, wa, hb, lb, wb = (np.asarray(z, float).reshape(-1) for z in (ha, la, wa, hb, lb, wb))
    ua, pa = _axes(ha)
    ub, pb = _axes(hb)
    d, w = cb - ca, vb - va
    enter = np.zeros(np.broadcast_shapes(ca.shape, cb.shape)[0])
    leave = np.full_like(enter, np.inf)
    for n in (ua, pa, ub, pb):
        r = (0.5 * la * np.abs(_dot(ua, n)) + 0.5 * wa * np.abs(_dot(pa, n)) + 0.5 * lb * np.abs(_dot(ub, n))
             + 0.5 * wb * np.abs(_dot(pb, n)) + touch_m)
        dn, wn = _dot(d, n), _dot(w, n)
        moving = wn != 0
        safe = np.where(moving, wn, 1.0)
        t1, t2 = (-r - dn) / safe, (r - dn) / safe
        still_in = np.abs(dn) <= r
        enter = np.maximum(enter, np.where(moving, np.minimum(t1, t2), np.where(still_in, -np.inf, np.inf)))
        leave = np.minimum(leave, np.where(moving, np.maximum(t1, t2), np.where(still_in, np.inf, -np.inf)))
    return np.where((enter <= leave) & (enter <= horizon_s), enter, np.inf)


def min_ttc2d_s(traj, rows: Rows | None = None, params: TTC2D = TTC2D()) -> float | None:
    """Smallest 2-D TTC between an ego and any other vehicle over a run, clamped at the horizon, s."""
    if len(traj) == 0 or not traj["is_ego"].to_numpy(bool).any():
        return None
    s = Rows.of(traj) if rows is None else rows
    vel = traj[["vx", "vy"]].to_numpy(float)  # rows in the table's order, as Rows
    xy = np.column_stack([s.x, s.y])
    hd_max = 0.5 * float(np.hypot(s.length, s.width).max())
    v_max = float(np.hypot(vel[:, 0], vel[:, 1]).max())
    best = float(params.horizon_s)
    r = s.min_search_m
    while True:
        i, j = s.pairs_within(r)
        for k in range(0, len(i), CHUNK):
            a, b = i[k:k + CHUNK], j[k:k + CHUNK]
            t = ttc_rectangles(xy[a], s.heading[a], s.length[a], s.width[a], vel[a],
                               xy[b], s.heading[b], s.length[b], s.width[b], vel[b], best, params.touch_m)
            if len(t):
                best = min(best, float(t.min()))
        need = 2.0 * hd_max + 2.0 * v_max * best
        if need <= r or r >= s.extent_m:
            return best
        r = need


class MinTTC2D(Metric):
    """min_ttc2d_s: the smallest constant-velocity 2-D time to footprint contact of an ego, s; persons
    count as the rectangles of their recorded length and width."""

    keys = Keys(("min_ttc2d_s",))

    def compute(self, run: RunResult) -> dict:
        if run.persons is None or run.persons.empty:
            return {"min_ttc2d_s": min_ttc2d_s(run.traj, pair_rows(run))}
        both = recorded(run).sort_values(["step", "id"], kind="stable").reset_index(drop=True)
        return {"min_ttc2d_s": min_ttc2d_s(both, Rows.of(both, road_apart(run)))}
