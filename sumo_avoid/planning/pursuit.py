"""Pure-pursuit path tracking: a planned polyline -> one desired velocity (m/s, world frame).

The car heads for the point ``lookahead`` metres further along the path than its own projection, seen
from the point it turns about (``axle_m`` behind its centre: the kinematic actuator's ``rear_axle_m``, 0 by
default; aimed at from the centre, a car turning about a rear axle 1.325 m back cut inside each bend: seed
004's field, seeds 1-3, took 110 / 54 / 62 s, from the axle 55 / 56 / 54 s, turning about the centre 35 /
62 / 34 s); the kinematic actuator then turns it towards that direction within its yaw and lateral
limits, which is pure pursuit's circular arc. Its speed is the smallest of the cruise speed, the speed of
the pursuit arc (curvature 2 sin(alpha) / lookahead, alpha the angle between heading and the
lookahead direction) at ``lat_accel_mps2``, and, for every path corner ahead, the speed from which
the car can brake at ``decel_mps2`` to the corner's speed sqrt(lat_accel R), R = lookahead /
(2 sin(theta / 2)) the radius of the arc that cuts a corner of turning angle theta. Pure numpy.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.geometry import wrap_angle
from sumo_avoid.road.polyline import arc_lengths, polyline_point_at


def corner_angles(path) -> np.ndarray:
    """(P-2,) turning angle at each inner vertex of a polyline, rad in [0, pi]."""
    d = np.diff(np.asarray(path, float), axis=0)
    h = np.arctan2(d[:, 1], d[:, 0])
    return np.abs((np.diff(h) + np.pi) % (2 * np.pi) - np.pi)


def aim_angle(path, s_ego: float, pos, heading: float, lookahead_m: float) -> float:
    """Angle from the heading to the look-ahead point, rad in (-pi, pi] (positive: to the left)."""
    aim = polyline_point_at(path, s_ego + lookahead_m) - np.asarray(pos, float)
    return float(wrap_angle(np.arctan2(aim[1], aim[0]) - heading))


def corridor_gap(points, pos, heading: float, half_length_m: float, half_width_m: float) -> float:
    """Distance from the front of a car (centre ``pos``, ``heading``) to the nearest of ``points``
    in the strip ahead of it ``half_width_m`` either side of its centre line, m (inf: none)."""
    rel = np.asarray(points, float).reshape(-1, 2) - np.asarray(pos, float)
    c, s = np.cos(heading), np.sin(heading)
    x = rel[:, 0] * c + rel[:, 1] * s - half_length_m
    y = -rel[:, 0] * s + rel[:, 1] * c
    ahead = (x > -half_length_m) & (np.abs(y) <= half_width_m)
    return float(np.maximum(x[ahead], 0.0).min(initial=np.inf))


def cone_gap(points, pos, heading: float, half_length_m: float, half_angle_rad: float) -> float:
    """Distance from the front of a car to the nearest of ``points`` within ``half_angle_rad`` of
    its heading (seen from its centre), m (inf: none)."""
    rel = np.asarray(points, float).reshape(-1, 2) - np.asarray(pos, float)
    d = np.hypot(rel[:, 0], rel[:, 1])
    bearing = np.abs(wrap_angle(np.arctan2(rel[:, 1], rel[:, 0]) - heading))
    return float(np.maximum(d[bearing <= half_angle_rad] - half_length_m, 0.0).min(initial=np.inf))


def pursuit_velocity(path, s_ego: float, pos, heading: float, cruise_mps: float, lookahead_m: float,
                     lat_accel_mps2: float, decel_mps2: float, max_course_rad: float = np.pi,
                     axle_m: float = 0.0) -> np.ndarray:
    """(2,) desired velocity for a car at ``pos`` (arc length ``s_ego`` on ``path``) with ``heading``.
    The direction stays within ``max_course_rad`` of the heading (forward driving: a look-ahead
    point behind the car is turned towards at the sharpest allowed course, not reversed to)."""
    path = np.asarray(path, float)
    pos = np.asarray(pos, float)
    axle = pos - axle_m * np.array([np.cos(heading), np.sin(heading)])  # pure pursuit steers the rear axle
    alpha = aim_angle(path, s_ego, axle, heading, lookahead_m + axle_m)
    if float(np.hypot(*(polyline_point_at(path, s_ego + lookahead_m) - pos))) < 1e-6:
        return np.zeros(2)
    sin_a = abs(np.sin(alpha)) if np.cos(alpha) > 0 else 1.0  # behind the car: tightest turn
    course = heading + float(np.clip(alpha, -max_course_rad, max_course_rad))
    aim = np.array([np.cos(course), np.sin(course)])
    speed = min(cruise_mps, np.sqrt(lat_accel_mps2 * lookahead_m / max(2.0 * sin_a, 1e-9)))
    if len(path) > 2:
        s_v = arc_lengths(path)[1:-1]
        ahead = s_v > s_ego
        theta = corner_angles(path)[ahead]
        radius = lookahead_m / np.maximum(2.0 * np.sin(theta / 2.0), 1e-9)
        v_corner = np.sqrt(lat_accel_mps2 * radius + 2.0 * decel_mps2 * (s_v[ahead] - s_ego))
        speed = min(speed, float(v_corner.min(initial=np.inf)))
    return speed * aim


def arena_bounds(walls, margin_m: float):
    """(xmin, ymin, xmax, ymax) the waypoints keep to: the walls' box shrunk by ``margin_m``; None without walls."""
    if walls is None:
        return None
    w = np.asarray(walls, float)
    return (*(w.min(axis=0) + margin_m), *(w.max(axis=0) - margin_m))


def rest_of(path, s_m: float, pos) -> np.ndarray:
    """``pos``, then the path's vertices beyond arc length ``s_m`` (warm start; the clearance trigger)."""
    return np.concatenate([np.asarray(pos, float)[None], path[np.searchsorted(arc_lengths(path), s_m, side="right"):]])
