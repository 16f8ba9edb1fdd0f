"""Short-term memory of radar returns (a minimal object list, as radar ECUs output).

A forward radar loses a car as soon as it is beside the ego (outside the field of view), exactly
when a lane change back would hit it. The tracker keeps each return for ``memory_s`` after it was
last seen, coasting it at the velocity estimated from that return (:func:`.perception.velocity_estimate`:
motion along the ego's heading that explains the radial speed) while it stays outside
the field of view or beyond the range. A remembered return that should be visible now but is not
matched by a new return within ``gate_m`` is dropped. No target ids are used.
Output: a :class:`~.radar.Detections` whose rows are the current returns followed by the coasted
ones, range and azimuth recomputed from each ego's current sensor pose (azimuths may lie outside
the field of view), so controllers read it exactly like a scan.
"""
from __future__ import annotations

import math

import numpy as np

from .perception import velocity_estimate
from .radar import Detections


class Tracker:
    def __init__(self, memory_s: float, fov_deg: float, max_range_m: float, gate_m: float = 3.0):
        self.memory_s = memory_s
        self.half = math.radians(fov_deg) / 2
        self.max_range_m = max_range_m
        self.gate_m = gate_m
        self._ids: tuple[str, ...] = ()  # the egos of the last scan (index space of _e)
        self._e = np.zeros(0, dtype=int)  # (M,) ego index (into _ids) of each remembered return
        self._p = np.zeros((0, 2))  # world position when last seen, m
        self._v = np.zeros((0, 2))  # estimated velocity, m/s
        self._t = np.zeros(0)  # time last seen, s
        self._scan_time = -math.inf

    def update(self, det: Detections) -> Detections:
        """Fold in a scan (a held scan changes nothing) and return current + coasted returns."""
        now = det.time_s
        if det.ego_ids != self._ids:  # egos came or went: re-index the memory, forget the gone
            ego_idx = {v: i for i, v in enumerate(det.ego_ids)}
            e = np.array([ego_idx.get(v, -1) for v in self._ids] + [-1], dtype=int)[self._e]
            k = np.flatnonzero(e >= 0)
            self._e, self._p, self._v, self._t = e[k], self._p[k], self._v[k], self._t[k]
            self._ids = det.ego_ids
        if now > self._scan_time:
            self._scan_time = now
            a = det.sensor_heading[det.ego] + det.azimuth_rad
            u = np.column_stack([np.cos(a), np.sin(a)])
            p_new = det.sensor_pos[det.ego] + det.range_m[:, None] * u
            v_new = velocity_estimate(det)
            keep = now - self._t <= self.memory_s
            e_old = self._e
            r, az, pred = self._polar(det, e_old, now)
            keep &= ~((np.abs(az) <= self.half) & (r <= self.max_range_m))  # should be seen now: trust the scan
            if keep.any() and det.n:
                d = np.hypot(*(pred[:, None, :] - p_new[None, :, :]).transpose(2, 0, 1))
                d = np.where(e_old[:, None] == det.ego[None, :], d, np.inf)
                keep &= d.min(axis=1) > self.gate_m  # re-observed: the new return replaces it
            k = np.flatnonzero(keep)
            self._e = np.concatenate([det.ego, self._e[k]])
            self._p = np.concatenate([p_new, self._p[k]])
            self._v = np.concatenate([v_new, self._v[k]])
            self._t = np.concatenate([np.full(det.n, now), self._t[k]])
        e = self._e
        r, az, _ = self._polar(det, e, now)
        a = det.sensor_heading[e] + az
        u = np.column_stack([np.cos(a), np.sin(a)])
        vr = np.einsum("ij,ij->i", self._v - det.sensor_vel[e], u)
        n_old = len(e) - det.n
        return Detections(now, det.ego_ids, det.sensor_pos, det.sensor_heading, det.sensor_vel, e, r, az, vr,
                          det.target + ("",) * n_old)

    def _polar(self, det, e, now):
        pred = self._p + self._v * (now - self._t)[:, None]
        rel = pred - det.sensor_pos[e] if len(e) else np.zeros((0, 2))
        r = np.hypot(rel[:, 0], rel[:, 1])
        az = (np.arctan2(rel[:, 1], rel[:, 0]) - det.sensor_heading[e] + np.pi) % (2 * np.pi) - np.pi
        return r, az, pred
