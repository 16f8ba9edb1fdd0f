"""What one ego's radar has revealed of the static world: a growing set of obstacle points.

The radar (:mod:`sumo_avoid.sensing.radar`) reports one return per target and scan, at the
target's nearest visible point, never its id. A planner that only kept those points would route
straight through the unseen body behind a face it saw head-on, so each static return also marks
its *shadow*, points every ``shadow_step_m`` along the line of sight behind it up to
``shadow_depth_m``, and its *face*, points at the same spacing across the line of sight up to
``face_half_width_m`` either side (at the nearest point of a convex obstacle its surface is
perpendicular to the line of sight, or it is a corner): the obstacle is assumed to be at least
that deep and that wide.
Points are kept once per ``cell_m`` square (the first one seen there), so the map grows with the
area revealed, not with the number of scans. A return farther than ``new_gap_m`` from every return
seen before is a *new obstacle* (the planner's replanning trigger). Each point remembers the
range its return was measured at (its shadow and face points that of their return): the radar's
error across the line of sight grows with range. With ``refine`` (the road case), a cell hit again
from a shorter range takes the new, more accurate point. Pure numpy.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.geometry import footprint_corners

from sumo_avoid.sensing.perception import velocity_estimate

_KEY = 1 << 32  # cell (i, j) -> one int64 key i * 2^32 + j


class RadarMap:
    def __init__(self, cell_m: float, shadow_depth_m: float, shadow_step_m: float, new_gap_m: float,
                 face_half_width_m: float = 0.0, refine: bool = False):
        self.cell_m = cell_m
        self.refine = refine
        step = shadow_step_m if shadow_step_m > 0 else np.inf
        self.shadow = np.arange(1, int(shadow_depth_m / step) + 1) * step  # depths behind a return, m
        side = np.arange(1, int(face_half_width_m / step) + 1) * step
        self.face = np.concatenate([-side[::-1], side])  # offsets across the line of sight, m
        self.new_gap_m = new_gap_m
        self._cells: set[int] = set()
        self._xy = np.zeros((64, 2))  # kept points (the first len(self) rows), m
        self._range = np.zeros(64)  # per point: range of the return it came from, m
        self._returns = np.zeros((0, 2))  # one return per cell (not their shadows): the new-obstacle test
        self._return_cells: set[int] = set()
        self._index: dict[int, int] = {}  # cell -> index of its point
        self._last_seen: list[float] = []  # per point: the last scan that put a point in its cell, s
        self.rows: list[tuple] = []  # (time_s, x, y, is_return) of each kept point

    @property
    def points(self) -> np.ndarray:
        """(M, 2) every kept point, in the order they were added, m."""
        return self._xy[:len(self._last_seen)].copy()

    def seen_since(self, time_s: float) -> tuple[np.ndarray, np.ndarray]:
        """(points (M', 2) m, their ranges (M',) m): the kept points whose cell some scan at or
        after ``time_s`` hit again (a map that forgets: on a road, traffic that stood and drove on
        leaves no obstacle behind), and the range each was measured at."""
        n = len(self._last_seen)
        keep = np.asarray(self._last_seen, float) >= time_s
        return self._xy[:n][keep], self._range[:n][keep]

    def __len__(self) -> int:
        return len(self.rows)

    def add(self, sensor_pos, returns, time_s: float) -> bool:
        """Fold in static returns (K, 2) seen from ``sensor_pos`` (K, 2) or (2,). Returns True when
        one of them is a new obstacle."""
        ret = np.asarray(returns, float).reshape(-1, 2)
        if len(ret) == 0:
            return False
        new = farther_than(ret, self._returns, self.new_gap_m)
        sight = ret - np.broadcast_to(np.asarray(sensor_pos, float), ret.shape)
        u = sight / np.maximum(np.hypot(*sight.T), 1e-9)[:, None]
        behind = (ret[:, None] + self.shadow[None, :, None] * u[:, None]).reshape(-1, 2)
        across = (ret[:, None] + self.face[None, :, None] * np.column_stack([-u[:, 1], u[:, 0]])[:, None]).reshape(-1, 2)
        pts = np.concatenate([ret, behind, across])
        dist = np.hypot(*sight.T)
        rng = np.concatenate([dist, np.repeat(dist, len(self.shadow)), np.repeat(dist, len(self.face))])
        is_ret = np.arange(len(pts)) < len(ret)
        ij = np.floor(pts / self.cell_m).astype(np.int64)
        keys = ij[:, 0] * _KEY + ij[:, 1]
        keep, seen = [], []
        n0 = len(self._last_seen)  # points before this scan (those of this scan are written below)
        for k, key in enumerate(keys.tolist()):  # a few dozen per scan
            if key not in self._cells:
                self._cells.add(key)
                self._index[key] = len(self._last_seen)
                self._last_seen.append(time_s)
                keep.append(k)
            else:
                i = self._index[key]
                self._last_seen[i] = time_s
                if self.refine and i < n0 and rng[k] < self._range[i]:  # measured closer: more accurate
                    self._xy[i], self._range[i] = pts[k], rng[k]
            if k < len(ret) and key not in self._return_cells:  # a return where a shadow was is still a return
                self._return_cells.add(key)
                seen.append(k)
        if keep:
            n = len(self._last_seen)
            if n > len(self._xy):
                cap = 2 * n
                self._xy = np.concatenate([self._xy, np.zeros((cap - len(self._xy), 2))])
                self._range = np.concatenate([self._range, np.zeros(cap - len(self._range))])
            self._xy[n - len(keep):n], self._range[n - len(keep):n] = pts[keep], rng[keep]
            self.rows.extend((time_s, float(x), float(y), bool(r)) for (x, y), r in zip(pts[keep], is_ret[keep]))
        if seen:
            self._returns = np.concatenate([self._returns, ret[seen]])
        return new


def static_returns(obs, vid: str, static_speed_mps: float, along: float | None = None, min_cos: float = 0.0):
    """Ego ``vid``'s radar returns (every mount, tracker memory included) whose estimated velocity
    (:func:`~sumo_avoid.sensing.perception.velocity_estimate`, traffic taken to move along ``along``
    (rad) if given, else along the sensor's boresight) is below ``static_speed_mps``:
    (points (K, 2), sensor positions (K, 2)). Returns whose line of sight makes an angle with
    ``along`` whose |cos| is below ``min_cos`` are left out: there the radial speed cannot tell a
    standing object from traffic passing beside the ego (a car abeam closes at ~0 m/s). Empty
    without a radar."""
    pts, src = [np.zeros((0, 2))], [np.zeros((0, 2))]
    for det in obs.detections or ():
        k = det.of(vid)
        if len(k) == 0:
            continue
        v = velocity_estimate(det, k, along=along)
        still = np.hypot(*v.T) < static_speed_mps
        if along is not None and min_cos > 0.0:
            sight = det.sensor_heading[det.ego[k]] + det.azimuth_rad[k]
            still &= np.abs(np.cos(sight - along)) >= min_cos
        pts.append(det.points()[k[still]])
        src.append(det.sensor_pos[det.ego[k[still]]])
    return np.concatenate(pts), np.concatenate(src)


def sampled_edges(polygons, step_m: float) -> np.ndarray:
    """Points every ``step_m`` along the edges of each polygon (the truth map)."""
    out = [np.zeros((0, 2))]
    for poly in polygons:
        poly = np.asarray(poly, float)
        for a, b in zip(poly, np.roll(poly, -1, axis=0)):
            k = max(1, int(np.ceil(np.hypot(*(b - a)) / step_m)))
            out.append(a + np.linspace(0.0, 1.0, k, endpoint=False)[:, None] * (b - a))
    return np.concatenate(out)


def standing_edges(snap, row: int, static_speed_mps: float, radius_m: float, step_m: float) -> np.ndarray:
    """Ground truth's counterpart of the radar's static returns on a road: points every ``step_m``
    along the footprints of the road users (vehicles and persons, other egos included) within
    ``radius_m`` of snapshot ``row`` (the ego, left out) that move slower than ``static_speed_mps``."""
    near = np.hypot(*(snap.pos - snap.pos[row]).T) < radius_m
    near &= np.hypot(*snap.vel.T) < static_speed_mps
    near[row] = False
    k = np.flatnonzero(near)
    return sampled_edges(footprint_corners(snap.pos[k], snap.heading[k], snap.length[k], snap.width[k]), step_m)


def farther_than(pts: np.ndarray, known: np.ndarray, gap_m: float) -> bool:
    """Does a point of ``pts`` lie farther than ``gap_m`` from every point of ``known``?"""
    if not len(pts):
        return False
    if not len(known):
        return True
    return bool((np.hypot(*(pts[:, None, :] - known[None, :, :]).transpose(2, 0, 1)).min(axis=1) > gap_m).any())
