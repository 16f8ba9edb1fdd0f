"""One ego's road in its route frame (SPEC §5), for every road-going controller.

Per step :meth:`RoadView.scene` maps what the ego perceives into Frenet coordinates (s along the
reference path, d across it, positive left; :class:`~sumo_avoid.core.frenet.RouteFrame`): the ego,
the other vehicles' footprints (centre, heading relative to the path, length, width, velocity
(s_dot, d_dot)) and the bounds of the lanes of its own direction
(:class:`~sumo_avoid.core.lanes.RouteLanes`). Vehicles wholly outside those lanes (oncoming traffic
beyond the centre line, cars on a road nearby) are left out: the ego keeps to its lanes, and one
that enters them is an obstacle from then on. In that frame a bend or a turn is straight, so a
field computed there keeps the car in its lane through it; :meth:`RoadView.to_xy_velocity` maps
the command back. A footprint's shape is kept as a rectangle in (s, d) (its curvature over a few
metres is neglected). docs/road_frame.md has the formulas.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from sumo_avoid.core.frenet import RouteFrame
from sumo_avoid.core.geometry import wrap_angle
from sumo_avoid.core.lanes import RouteLanes
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.sensing.perception import obstacle_vehicles

#: Vehicles farther than this across the path are not part of the ego's road scene, m.
MAX_ABS_D_M = 20.0
#: A vehicle whose footprint stays this far outside the ego's lanes is no obstacle to it, m.
OUTSIDE_MARGIN_M = 0.2
#: Window of the ego's own projection around its last arc length, m.
TRACK_WINDOW_M = 30.0


@dataclass(frozen=True)
class FrenetScene:
    """The ego and what it perceives, in its route frame at one step."""

    s: float  # ego centre arc length, m
    d: float  # ego centre lateral offset, m (left > 0)
    heading: float  # ego heading relative to the path's tangent at s, rad
    vel: np.ndarray  # (2,) ego velocity (s_dot, d_dot), m/s
    length: float
    width: float
    o_pos: np.ndarray  # (O, 2) other vehicles' centres (s, d), m
    o_heading: np.ndarray  # (O,) relative to the path's tangent at their s, rad
    o_length: np.ndarray  # (O,)
    o_width: np.ndarray  # (O,)
    o_vel: np.ndarray  # (O, 2) (s_dot, d_dot), m/s
    corridor: Callable  # s (N,) -> (d_lo (N,), d_hi (N,)): bounds of the ego's lanes, m

    @property
    def q(self) -> np.ndarray:
        return np.array([self.s, self.d])


class RoadView:
    """The route frame and lanes of one ego, with its arc length tracked from step to step."""

    def __init__(self, task: EgoTask):
        self.frame = RouteFrame.from_polyline(task.path)
        self.lanes = RouteLanes(task.lanes) if task.lanes else None
        gs, gd = self.frame.to_frenet(np.asarray(task.goal, float)[None, :])
        self.goal = np.array([gs[0], gd[0]])
        self._s: float | None = None

    @property
    def length_m(self) -> float:
        return self.frame.length_m

    def locate(self, xy) -> tuple[float, float]:
        """(s, d) of the ego's centre, projected near where it was last step (a path that passes
        a place twice is not confused)."""
        hint = None if self._s is None else np.array([self._s])
        s, d = self.frame.to_frenet(np.asarray(xy, float)[None, :], hint, TRACK_WINDOW_M)
        self._s = float(s[0])
        return float(s[0]), float(d[0])

    def corridor(self, s) -> tuple[np.ndarray, np.ndarray]:
        if self.lanes is None:
            s = np.atleast_1d(np.asarray(s, float))
            return np.full(len(s), -np.inf), np.full(len(s), np.inf)
        return self.lanes.corridor(s)

    def scene(self, obs: Observation, row: int, sense_radius_m: float) -> FrenetScene:
        snap = obs.snapshot
        q = snap.pos[row]
        s, d = self.locate(q)
        h_path = float(self.frame.heading_at(s)[0])
        v_s, v_d = self.frame.velocity_to_frenet(s, d, snap.vel[row][None, :])
        o_pos, o_hd, o_len, o_wid, o_vel = obstacle_vehicles(obs, row, q, sense_radius_m)
        if len(o_pos):
            os_, od = self.frame.to_frenet(o_pos, np.full(len(o_pos), s), sense_radius_m)
            keep = np.isfinite(os_) & (np.abs(od) < MAX_ABS_D_M) & (np.abs(os_ - s) < sense_radius_m)
            os_, od = os_[keep], od[keep]
            o_hd, o_len, o_wid, o_vel = o_hd[keep], o_len[keep], o_wid[keep], o_vel[keep]
            o_rel = wrap_angle(o_hd - self.frame.heading_at(os_))
            # a vehicle wholly outside the ego's lanes (oncoming traffic beyond the centre line,
            # a car on a road nearby) is behind a bound the ego keeps to: not an obstacle to it
            half = 0.5 * (np.abs(np.sin(o_rel)) * o_len + np.abs(np.cos(o_rel)) * o_wid)
            lo, hi = self.corridor(os_)
            keep = (od + half > lo - OUTSIDE_MARGIN_M) & (od - half < hi + OUTSIDE_MARGIN_M)
            os_, od, o_rel, o_len, o_wid, o_vel = os_[keep], od[keep], o_rel[keep], o_len[keep], o_wid[keep], o_vel[keep]
            vs, vd = self.frame.velocity_to_frenet(os_, od, o_vel)
            o_pos, o_vel = np.column_stack([os_, od]), np.column_stack([vs, vd])
        else:
            o_rel = np.zeros(0)
        return FrenetScene(s, d, float(wrap_angle(snap.heading[row] - h_path)), np.array([v_s[0], v_d[0]]),
                           float(snap.length[row]), float(snap.width[row]),
                           o_pos.reshape(-1, 2), o_rel, o_len, o_wid, o_vel.reshape(-1, 2), self.corridor)

    def to_xy_velocity(self, s: float, d: float, v_frenet, lead_s: float = 0.0) -> np.ndarray:
        """(2,) world velocity of a Frenet command (s_dot, d_dot), with the command's magnitude (the
        (1 - kappa d) factor changes the direction, not the speed asked for). The frame is taken
        ``lead_s`` seconds of travel ahead of s: the car drives the command during the next step,
        while the road turns under it (curvature feed-forward; without it a car lags to the
        outside of every bend)."""
        v = np.asarray(v_frenet, float)
        speed = float(np.hypot(*v))
        if speed < 1e-12:
            return np.zeros(2)
        s_ff = s + max(float(v[0]), 0.0) * lead_s
        xy = self.frame.velocity_to_xy(s_ff, d, v[0], v[1])[0]
        n = float(np.hypot(*xy))
        return xy / n * speed if n > 1e-12 else np.zeros(2)

    def curve_speed(self, s: float, a_lat_mps2: float, decel_mps2: float) -> float:
        """Speed for the road ahead from its curvature (RouteFrame.curve_speed_limit, full envelope)."""
        return float(self.frame.curve_speed_limit(s, np.inf, a_lat_mps2, decel_mps2)[0])
