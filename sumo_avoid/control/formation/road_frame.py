"""The formation on a road (SPEC §3 on SPEC §5's route frame): every member, vehicle and goal mapped
into the **leader's** route frame (s along its route's reference path, d across it, positive left;
:class:`~sumo_avoid.control.road_view.RoadView`), the formation controller's step run there, and its
velocity commands (s_dot, d_dot) mapped back to the plane. In that frame the road is straight, so
the formation frame's heading is the road's direction and a bend does not swing the slots.

The drivable corridor is the walls: the lanes of the route's direction
(:class:`~sumo_avoid.road.carriageway.Carriageway`, d_lo(s) <= d <= d_hi(s)).

* **W_max**: the corridor narrows the free width like an obstacle: the intervals below the highest
  d_lo and above the lowest d_hi over [-depth, lookahead] about the leader are occupied.
* **Safety**: each member's footprint keeps ``shield_margin_m`` from both bounds through the shield's
  barrier (v . n >= -k (gap - margin), n = +d from the right bound, -d from the left); the bounds are
  no part of the potential field (a repulsion growing with the distance to a goal a kilometre away
  would push every car to the middle of the road).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from sumo_avoid.control.road_view import RoadView
from sumo_avoid.core.geometry import wrap_angle
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.road.carriageway import Carriageway

#: Vehicles farther than this along the road from the leader are moved out of the scene, m.
SCENE_M = 250.0
#: Occupied intervals beyond the corridor reach this far out, m.
_BEYOND_M = 100.0


class RoadFrame:
    """The leader's route frame and carriageway, and the maps into and out of it."""

    def __init__(self, leader: EgoTask):
        self.view = RoadView(leader)
        self.lanes = Carriageway(leader.lanes) if leader.lanes else None
        self.s_lead = 0.0

    def to_frenet(self, xy, hint: float) -> np.ndarray:
        """(N, 2) points (s, d), projected within SCENE_M of ``hint``."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        s, d = self.view.frame.to_frenet(xy, np.full(len(xy), hint), SCENE_M)
        return np.column_stack([s, d])

    def polygons(self, polys) -> tuple[np.ndarray, ...]:
        """Static polygons (each (k, 2)) with their vertices mapped to (s, d)."""
        return tuple(self.to_frenet(p, float(self.view.frame.to_frenet(p.mean(axis=0)[None])[0][0]))
                     for p in polys)

    def corridor(self, s) -> tuple[np.ndarray, np.ndarray]:
        if self.lanes is None:
            s = np.atleast_1d(s)
            return np.full(len(s), -np.inf), np.full(len(s), np.inf)
        return self.lanes.corridor(s)

    def enter(self, obs: Observation, lead_row: int) -> Observation:
        """The observation with its snapshot in the leader's frame: centres (s, d), velocities
        (s_dot, d_dot), headings relative to the path; other vehicles beyond SCENE_M along the road far
        away (the members never: a member left behind must still find its way back)."""
        snap = obs.snapshot
        self.s_lead, _ = self.view.locate(snap.pos[lead_row])
        q = self.to_frenet(snap.pos, self.s_lead)
        far = (~np.isfinite(q).all(axis=1) | (np.abs(q[:, 0] - self.s_lead) > SCENE_M)) & ~snap.is_ego
        q = np.where(far[:, None], [self.s_lead - 1e5, 1e5], q)
        vs, vd = self.view.frame.velocity_to_frenet(q[:, 0], q[:, 1], snap.vel)
        hd = wrap_angle(snap.heading - self.view.frame.heading_at(q[:, 0]))
        fs = replace(snap, pos=q, vel=np.column_stack([vs, vd]), heading=hd, index={})
        return replace(obs, snapshot=fs)

    def leave(self, fobs: Observation, v_frenet) -> np.ndarray:
        """(E, 2) world velocities of the commands (s_dot, d_dot) of the egos of ``fobs``."""
        q = fobs.snapshot.pos[fobs.ego_rows]
        return np.array([self.view.to_xy_velocity(s, d, v) for (s, d), v in zip(q, np.asarray(v_frenet))]).reshape(-1, 2)

    @staticmethod
    def field_mask(pos, length, width, polys, mask, lead_k, clear_m: float) -> np.ndarray:
        """(E, O) which hazards enter the potential field on a road: for the leader the vehicles
        wholly ahead of its front bumper that reach within ``clear_m`` of its strip along the road
        (those in its way); none for the followers, who hold their slots (or the leader's trail).
        Everything else is left to the shield: a repulsion ~ 1/rho^2 from the car in the next lane,
        1.7 m away, would throw a car across the road."""
        out = np.zeros_like(mask)
        if not len(polys) or lead_k is None:
            return out
        q, h = pos[lead_k], 0.5 * width[lead_k] + clear_m
        out[lead_k] = mask[lead_k] & (polys[:, :, 0].min(axis=1) > q[0] + 0.5 * length[lead_k]) \
            & (polys[:, :, 1].max(axis=1) > q[1] - h) & (polys[:, :, 1].min(axis=1) < q[1] + h)
        return out

    @staticmethod
    def carrot(q, goal, lookahead_m: float, gap_centre: float) -> np.ndarray:
        """The leader's goal on a road: ``lookahead_m`` (``carrot_m``) ahead of it, across at the centre of the free
        gap ahead (``gap_centre`` relative to it, from W_max), until the goal is nearer than that."""
        if goal[0] - q[0] <= lookahead_m:
            return goal
        return np.array([q[0] + lookahead_m, q[1] + gap_centre])

    def walls(self, pos, heading, length, width, margin_m: float, k_ps: float):
        """Barrier constraints of the corridor's bounds for the members (frame coordinates):
        (n (E, 2, 2), bounds (E, 2)); a footprint's half extent across the road 0.5 (|sin h| L + |cos h| W)."""
        lo, hi = self.corridor(pos[:, 0])
        half = 0.5 * (np.abs(np.sin(heading)) * length + np.abs(np.cos(heading)) * width)
        gap = np.column_stack([pos[:, 1] - half - lo, hi - pos[:, 1] - half])
        n = np.broadcast_to(np.array([[0.0, 1.0], [0.0, -1.0]]), (len(pos), 2, 2))
        return n, -k_ps * (np.where(np.isfinite(gap), gap, 1e9) - margin_m)

    def occupied(self, d_lead: float, behind_m: float, ahead_m: float) -> np.ndarray:
        """(2, 2) lateral intervals [lo, hi] relative to the leader that the corridor leaves no room
        in over [s_lead - behind, s_lead + ahead]: below its highest right bound, above its lowest left."""
        s = np.linspace(self.s_lead - behind_m, self.s_lead + ahead_m, 25)
        lo, hi = self.corridor(s)
        if not np.isfinite(lo).all() or not np.isfinite(hi).all():
            return np.zeros((0, 2))
        a, b = float(lo.max()) - d_lead, float(hi.min()) - d_lead
        return np.array([[a - _BEYOND_M, a], [b, b + _BEYOND_M]])
