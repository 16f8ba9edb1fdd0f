"""Short-term memory of radar returns (a minimal object list, as radar ECUs output).

A forward radar loses a car as soon as it is beside the ego (outside the field of view), exactly
when a lane change back would hit it. The tracker keeps each return for ``memory_s`` after it was
last seen, coasting it at the velocity estimated from that return (:func:`.perception.velocity_estimate`:
motion along the ego's heading that explains the radial speed) while it stays outside
the field of view or beyond the range. A remembered return that should be visible now is dropped (the
scan is trusted); one out of view that a new return within ``gate_m`` matches is replaced by it, unless it stands
(:data:`STANDING_MPS`: the new return is another part of the same object, the part still in view); of
standing ones within :data:`SAME_PART_M` of each other the oldest is kept. No target ids are used.
With rear and side radars too, one memory serves them all (see :meth:`Tracker.update`).
Output: a :class:`~.radar.Detections` whose rows are the current returns followed by the coasted
ones, range and azimuth recomputed from each ego's current sensor pose (azimuths may lie outside
the field of view), so controllers read it exactly like a scan.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from sumo_avoid.core.types import Detections
from sumo_avoid.sensing.perception import velocity_estimate

_EGO_SEPARATION_M = 1e6  # egos' returns are kept apart in the search tree along a third axis
#: A remembered return estimated slower than this (m/s) stands: its coasted position is where it was seen.
STANDING_MPS = 0.5
#: ... and one remembered this close (m) to an older one is the same part of it seen again (noise ~0.1-0.3 m).
SAME_PART_M = 0.5


def _near_same_ego(p, e, q, f, gate_m: float) -> np.ndarray:
    """(len(p),) True where point p[i] of ego e[i] has a point q[j] of the same ego (f[j] == e[i])
    within gate_m: one k-d tree over (x, y, ego * 1e6), so other egos' points are never near."""
    tree = cKDTree(np.column_stack([q, f * _EGO_SEPARATION_M]))
    d, _ = tree.query(np.column_stack([p, e * _EGO_SEPARATION_M]), k=1, distance_upper_bound=gate_m)
    return d <= gate_m


class Tracker:
    def __init__(self, memory_s: float, fov_deg: float, max_range_m: float, gate_m: float = 3.0, views=None):
        """``views``: {mount: (fov_deg, max_range_m)} of mounts whose view differs (side radars);
        the others see ``fov_deg`` and ``max_range_m``."""
        self.memory_s = memory_s
        self.half = math.radians(fov_deg) / 2
        self.max_range_m = max_range_m
        self.views = {m: (math.radians(f) / 2, r) for m, (f, r) in (views or {}).items()}
        self.gate_m = gate_m
        self._ids: tuple[str, ...] = ()  # the egos of the last scan (index space of _e)
        self._e = np.zeros(0, dtype=int)  # (M,) ego index (into _ids) of each remembered return
        self._p = np.zeros((0, 2))  # world position when last seen, m
        self._v = np.zeros((0, 2))  # estimated velocity, m/s
        self._t = np.zeros(0)  # time last seen, s
        self._s = np.zeros(0, bool)  # labelled a person or cyclist
        self._scan_time = -math.inf

    def update(self, det, along=None):
        """Fold in a scan (a held scan changes nothing) and return current + coasted returns.

        ``det`` is one :class:`Detections` or a tuple of them, one per radar mount of the same egos
        (front first). With several mounts the memory is fused: a remembered return is dropped
        when it should be visible to any of them, and re-observation by any of them replaces it;
        the coasted returns are reported with the first (front) scan, the others as scanned.
        """
        scans = det if isinstance(det, tuple) else (det,)
        ref = scans[0]
        now = ref.time_s
        if ref.ego_ids != self._ids:  # egos came or went: re-index the memory, forget the gone
            ego_idx = {v: i for i, v in enumerate(ref.ego_ids)}
            e = np.array([ego_idx.get(v, -1) for v in self._ids] + [-1], dtype=int)[self._e]
            k = np.flatnonzero(e >= 0)
            self._e, self._p, self._v, self._t, self._s = e[k], self._p[k], self._v[k], self._t[k], self._s[k]
            self._ids = ref.ego_ids
        if now > self._scan_time:
            self._scan_time = now
            p_new = np.concatenate([d.points() for d in scans])
            # coasting velocity: motion along the traffic's direction at the ego if known (the route),
            # else along the sensor's boresight
            v_new = np.concatenate([velocity_estimate(d, along=None if along is None else np.asarray(along)[d.ego])
                                    for d in scans])
            e_new = np.concatenate([d.ego for d in scans])
            keep = now - self._t <= self.memory_s
            for d in scans:  # should be seen now by this radar: trust its scan
                r, az, pred = self._polar(d, self._e, now)
                half, rmax = self.views.get(d.mount, (self.half, self.max_range_m))
                keep &= ~((np.abs(az) <= half) & (r <= rmax))
            # re-observed (a new return of the same ego within gate_m): replaced -- unless it stands. Out of view,
            # a standing return is where it was seen; a new return near it is another part of the same object,
            # the part still in view (the beam's edge cuts it): a car standing askew beside the ego's path, its
            # near corner out of the front radar's view, was returned only from its far end, which put its box
            # 1.5 m too far away, and the ego touched the corner in passing (wildau_turns, radar, seeds 1-5)
            moving = np.hypot(self._v[:, 0], self._v[:, 1]) >= STANDING_MPS
            k = np.flatnonzero(keep & moving)
            if len(k) and len(e_new):
                keep[k[_near_same_ego(pred[k], self._e[k], p_new, e_new, self.gate_m)]] = False
            keep[self._thinned(np.flatnonzero(keep & ~moving), pred)] = False
            k = np.flatnonzero(keep)
            self._e = np.concatenate([e_new, self._e[k]])
            self._p = np.concatenate([p_new, self._p[k]])
            self._v = np.concatenate([v_new, self._v[k]])
            self._t = np.concatenate([np.full(len(e_new), now), self._t[k]])
            self._s = np.concatenate([d.vru_mask() for d in scans] + [self._s[k]])
        # the front scan's own rows and the coasted ones (the other mounts' current rows skipped)
        n_cur = sum(d.n for d in scans)
        rows = np.concatenate([np.arange(ref.n), np.arange(n_cur, len(self._e))]).astype(int)
        e = self._e[rows]
        r, az, _ = self._polar(ref, e, now, rows)
        a = ref.sensor_heading[e] + az
        u = np.column_stack([np.cos(a), np.sin(a)])
        vr = np.einsum("ij,ij->i", self._v[rows] - ref.sensor_vel[e], u)
        out = Detections(now, ref.ego_ids, ref.sensor_pos, ref.sensor_heading, ref.sensor_vel, e, r, az, vr,
                         ref.target + ("",) * (len(rows) - ref.n), ref.mount,
                         None if ref.vru is None and not self._s.any() else self._s[rows])
        return out if not isinstance(det, tuple) else (out,) + scans[1:]

    def _thinned(self, k, pred) -> np.ndarray:
        """Of the standing remembered returns ``k``, those within :data:`SAME_PART_M` of an older one of the same
        ego: the same part seen again (a cyclist at the beam's edge, in and out of view with the noise, piled
        up 20 returns otherwise), which the older one stands for from then on (its memory runs from the newer
        one's sighting); returns a metre apart along a car's side all stay."""
        drop, kept = [], []
        if len(k) < 2:
            return np.zeros(0, int)
        # only returns with another of the same ego within SAME_PART_M can be dropped or refreshed (usually none)
        pairs = cKDTree(np.column_stack([pred[k], self._e[k] * _EGO_SEPARATION_M])).query_pairs(
            SAME_PART_M, output_type="ndarray")
        if not len(pairs):
            return np.zeros(0, int)
        k = k[np.unique(pairs)]
        for i in k[np.lexsort((k, self._t[k]))]:  # oldest first
            j = np.asarray(kept, int)
            same = j[(np.hypot(*(pred[j] - pred[i]).T) < SAME_PART_M) & (self._e[j] == self._e[i])] if len(j) else j
            if len(same):
                drop.append(i)
                self._t[same[0]] = self._t[i]  # seen again: remembered from now on
            else:
                kept.append(i)
        return np.asarray(drop, int)

    def _polar(self, det, e, now, rows=slice(None)):
        pred = self._p[rows] + self._v[rows] * (now - self._t[rows])[:, None]
        rel = pred - det.sensor_pos[e] if len(e) else np.zeros((0, 2))
        r = np.hypot(rel[:, 0], rel[:, 1])
        az = (np.arctan2(rel[:, 1], rel[:, 0]) - det.sensor_heading[e] + np.pi) % (2 * np.pi) - np.pi
        return r, az, pred
