"""Turn radar detections into obstacle footprints a controller can use (no target ids used).

A radar return is one point (the nearest visible point of a target) with a radial speed. A
controller that expects footprints gets, per detection, an assumed car-sized box
(``ASSUMED_LENGTH_M`` x ``ASSUMED_WIDTH_M``) aligned with the ego's heading and placed just behind
the reflection point along the line of sight, moving with the ego's velocity plus the measured
radial speed explained by motion along the ego's heading (:func:`velocity_estimate`).
"""
from __future__ import annotations

import numpy as np

ASSUMED_LENGTH_M = 4.5
ASSUMED_WIDTH_M = 1.8


def velocity_estimate(det, k=None) -> np.ndarray:
    """(D,2) world velocity of returns ``k`` (all by default), m/s, from their radial speed only.

    The tangential component is unobservable in one return; road traffic moves mostly along the
    ego's heading h, so the target is taken to move along h at the speed s that explains the
    measured radial speed: (s h - v_ego) . u = v_r. Exact for parallel traffic and for stationary
    objects (s = 0). Where h . u < 0.3 (more than ~73 degrees off the heading) the radial-only
    estimate v_ego + v_r u is used instead.
    """
    k = np.arange(det.n) if k is None else k
    e = det.ego[k]
    h = det.sensor_heading[e]
    hd = np.column_stack([np.cos(h), np.sin(h)])
    a = h + det.azimuth_rad[k]
    u = np.column_stack([np.cos(a), np.sin(a)])
    vr = det.radial_speed_mps[k]
    ve = det.sensor_vel[e]
    c = (hd * u).sum(1)
    along = (vr + (ve * u).sum(1)) / np.where(np.abs(c) >= 0.3, c, 1.0)
    return np.where((np.abs(c) >= 0.3)[:, None], along[:, None] * hd, ve + vr[:, None] * u)


def perceived_obstacles(det, vid: str, length_m: float = ASSUMED_LENGTH_M, width_m: float = ASSUMED_WIDTH_M):
    """Obstacles seen by ego ``vid``: (pos (M,2), heading (M,), length (M,), width (M,), vel (M,2))."""
    k = det.of(vid)
    M = len(k)
    if M == 0:
        z = np.zeros(0)
        return np.zeros((0, 2)), z, z, z, np.zeros((0, 2))
    e = det.ego[k]
    h = det.sensor_heading[e]
    a = h + det.azimuth_rad[k]
    u = np.column_stack([np.cos(a), np.sin(a)])
    hd = np.column_stack([np.cos(h), np.sin(h)])
    nd = np.column_stack([-hd[:, 1], hd[:, 0]])
    depth = 0.5 * length_m * np.abs((u * hd).sum(1)) + 0.5 * width_m * np.abs((u * nd).sum(1))
    point = det.sensor_pos[e] + det.range_m[k][:, None] * u
    pos = point + depth[:, None] * u
    vel = velocity_estimate(det, k)
    return pos, h, np.full(M, length_m), np.full(M, width_m), vel


def obstacle_vehicles(obs, row: int, q, radius_m: float):
    """Other vehicles for the ego at snapshot ``row`` as (pos, heading, length, width, vel):
    from the radar when ``obs.detections`` is set, else ground truth within ``radius_m`` of q."""
    snap = obs.snapshot
    if getattr(obs, "detections", None) is not None:
        return perceived_obstacles(obs.detections, snap.ids[row])
    d = np.hypot(*(snap.pos - np.asarray(q, float)).T)
    o = np.flatnonzero((d < radius_m) & (np.arange(snap.n) != row))
    return snap.pos[o], snap.heading[o], snap.length[o], snap.width[o], snap.vel[o]
