"""Pure-pursuit path tracking: a planned polyline -> one desired velocity (m/s, world frame).

The car heads for the point ``lookahead`` metres further along the path than its own projection
(the kinematic actuator then turns it towards that direction within its yaw and lateral limits,
which is pure pursuit's circular arc). Its speed is the smallest of the cruise speed, the speed of
the pursuit arc (curvature 2 sin(alpha) / lookahead, alpha the angle between heading and the
lookahead direction) at ``lat_accel_mps2``, and, for every path corner ahead, the speed from which
the car can brake at ``decel_mps2`` to the corner's speed sqrt(lat_accel R), R = lookahead /
(2 sin(theta / 2)) the radius of the arc that cuts a corner of turning angle theta. Pure numpy.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.polyline import arc_lengths, polyline_point_at


def corner_angles(path) -> np.ndarray:
    """(P-2,) turning angle at each inner vertex of a polyline, rad in [0, pi]."""
    d = np.diff(np.asarray(path, float), axis=0)
    h = np.arctan2(d[:, 1], d[:, 0])
    return np.abs((np.diff(h) + np.pi) % (2 * np.pi) - np.pi)


def pursuit_velocity(path, s_ego: float, pos, heading: float, cruise_mps: float, lookahead_m: float,
                     lat_accel_mps2: float, decel_mps2: float) -> np.ndarray:
    """(2,) desired velocity for a car at ``pos`` (arc length ``s_ego`` on ``path``) with ``heading``."""
    path = np.asarray(path, float)
    pos = np.asarray(pos, float)
    target = polyline_point_at(path, s_ego + lookahead_m)
    aim = target - pos
    dist = float(np.hypot(*aim))
    if dist < 1e-6:
        return np.zeros(2)
    alpha = float(np.arctan2(aim[1], aim[0]) - heading)
    sin_a = abs(np.sin(alpha)) if np.cos(alpha) > 0 else 1.0  # behind the car: tightest turn
    speed = min(cruise_mps, np.sqrt(lat_accel_mps2 * lookahead_m / max(2.0 * sin_a, 1e-9)))
    if len(path) > 2:
        s_v = arc_lengths(path)[1:-1]
        ahead = s_v > s_ego
        theta = corner_angles(path)[ahead]
        radius = lookahead_m / np.maximum(2.0 * np.sin(theta / 2.0), 1e-9)
        v_corner = np.sqrt(lat_accel_mps2 * radius + 2.0 * decel_mps2 * (s_v[ahead] - s_ego))
        speed = min(speed, float(v_corner.min(initial=np.inf)))
    return speed * aim / dist
