"""``apf``: artificial potential field on a road (SPEC §2, seed 001).

Per ego and step:

* **Attraction** (SPEC §2, seed eq. 13-14, capped beyond ``d_att_m``) towards a *carrot*: the
  point ``lookahead`` metres ahead of the ego on the reference path of its route (lane centres
  joined through the junction), or the goal itself once it is closer than that. A straight-line
  pull to a goal round a corner would pin the car against the kerb.
* **Repulsion** (SPEC §2, seed eq. 3-8) ``K (1/rho - 1/rho0) / rho^2`` from every other vehicle's
  footprint (rho = footprint-to-footprint distance, direction from the obstacle's nearest point
  to the ego's) and, with its own gain and influence distance, from road edges and solid lines
  (the left border of each edge, i.e. the centre line between opposite directions).
* **Influence distance from speed and braking**: ``rho0 = rho0_min + max(cos(phi), 0) *
  (v_close^2 / (2 b) + t_h |v|)`` with ``phi`` the bearing of the obstacle from the heading and
  ``v_close`` the closing speed: an obstacle ahead is felt from the stopping distance, one beside
  only from ``rho0_min``.
* **Velocity**: the ego moves along F (direction F/|F|) at ``min(cruise, |F| * cruise / F_att_max,
  v_safe)``: at the potential's minimum it stops. ``v_safe`` is a speed governor: the speed from
  which the ego can stop behind whatever is in its corridor ahead even if that brakes to a stop,
  ``sqrt(v_lead^2 + 2 b (gap - s0))``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.config import field_doc
from sumo_avoid.core.geometry import (
    convex_distance,
    footprint_corners,
    point_segment_distance,
)
from sumo_avoid.core.polyline import polyline_point_at, polyline_project
from sumo_avoid.core.types import EgoTask, Needs, Observation
from sumo_avoid.sensing.perception import obstacle_vehicles


@dataclass(frozen=True)
class ApfParams:
    k_att: float = field_doc(1.0, doc="attraction gain K_att, 1/s (force in m/s units)")
    d_att_m: float = field_doc(10.0, doc="attraction is capped beyond this distance d, m")
    k_rep: float = field_doc(300.0, doc="vehicle/obstacle repulsion gain K_rep, m^3/s")
    rho0_min_m: float = field_doc(2.0, doc="influence distance beside an obstacle / at standstill, m")
    rho0_decel_mps2: float = field_doc(4.0, doc="braking used for the influence distance, m/s^2")
    rho0_headway_s: float = field_doc(0.8, doc="time headway added to the influence distance ahead, s")
    k_edge: float = field_doc(2.0, doc="road-edge and solid-line repulsion gain, m^3/s")
    rho0_edge_m: float = field_doc(0.8, doc="road-edge and solid-line influence distance, m")
    edge_lat_decel_mps2: float = field_doc(2.0, doc="lateral deceleration for the edge influence distance, m/s^2")
    edge_reaction_s: float = field_doc(0.5, doc="reaction time added to the edge influence distance, s")
    lookahead_min_m: float = field_doc(15.0, doc="smallest carrot distance along the route, m")
    lookahead_time_s: float = field_doc(1.5, doc="carrot distance per unit speed, s")
    sense_radius_m: float = field_doc(100.0, doc="obstacles farther than this are ignored, m")
    gov_decel_mps2: float = field_doc(4.0, doc="speed governor: braking it plans with, m/s^2")
    gov_standstill_m: float = field_doc(2.0, doc="speed governor: gap kept at standstill, m")
    gov_margin_m: float = field_doc(0.4, doc="speed governor: lateral margin of the corridor ahead, m")


@dataclass(frozen=True)
class Field:
    """Potential and force at candidate ego positions (C of them), plus the governor's speed."""

    U: np.ndarray  # (C,)
    F: np.ndarray  # (C, 2)
    v_safe: float  # m/s, for the first candidate (the ego's real position)


def attraction(q, target, k_att, d):
    """SPEC §2 capped attraction at points q (C,2): returns U (C,), F (C,2)."""
    diff = np.asarray(q, float) - np.asarray(target, float)
    rho = np.hypot(diff[:, 0], diff[:, 1])
    near = rho <= d
    U = np.where(near, 0.5 * k_att * rho**2, d * k_att * rho - 0.5 * k_att * d**2)
    scale = np.where(near, k_att, d * k_att / np.maximum(rho, 1e-12))
    return U, -scale[:, None] * diff


def repulsion(rho, direction, rho0, k_rep, rho_floor=0.2):
    """SPEC §2 repulsion for M obstacle distances rho (M,), unit directions (M,2) away from the
    obstacle, influence distances rho0 (M,): returns U (M,), F (M,2)."""
    r = np.maximum(np.asarray(rho, float), rho_floor)
    inside = r < rho0
    diff = np.where(inside, 1.0 / r - 1.0 / rho0, 0.0)
    U = 0.5 * k_rep * diff**2
    F = (k_rep * diff / r**2)[:, None] * direction
    return U, F


def _unit(v):
    n = np.hypot(v[..., 0], v[..., 1])
    return v / np.maximum(n, 1e-12)[..., None], n


class ApfController:
    """Plain potential field (no escape from local minima)."""

    needs = Needs(goals=True)
    metrics = ()  # metrics of its own beside the standard set

    def __init__(self, params: ApfParams, ctx):
        self.p = params
        self.road = ctx.road
        self.rng = ctx.rng()
        self.tasks: dict[str, EgoTask] = {}
        self.last_force: dict[str, float] = {}

    def add_ego(self, task: EgoTask) -> None:
        self.tasks[task.vid] = task

    def remove_ego(self, vid: str) -> None:
        self.tasks.pop(vid, None)

    def stats(self) -> dict:
        return {}

    # --- targets ---------------------------------------------------------------------------
    def carrot(self, task: EgoTask, q, speed: float, lateral_offset: float = 0.0) -> np.ndarray:
        lookahead = max(self.p.lookahead_min_m, self.p.lookahead_time_s * abs(speed))
        if np.hypot(*(task.goal - q)) <= lookahead and lateral_offset == 0.0:
            return task.goal
        s = polyline_project(task.path, q) + lookahead
        point = polyline_point_at(task.path, s)
        if lateral_offset:
            ahead = polyline_point_at(task.path, s + 1.0)
            t, _ = _unit(ahead - point)
            point = point + lateral_offset * np.array([-t[1], t[0]])
        return point

    # --- the field -------------------------------------------------------------------------
    def field(self, obs: Observation, row: int, q_cand: np.ndarray, target: np.ndarray,
              heading: float | None = None) -> Field:
        """Potential, force and governor speed for the ego at ``row`` placed at ``q_cand`` (C,2)
        (with its own heading, or ``heading`` in rad)."""
        p, snap = self.p, obs.snapshot
        q_cand = np.atleast_2d(np.asarray(q_cand, float))
        C = len(q_cand)
        h = snap.heading[row] if heading is None else heading
        L, W = snap.length[row], snap.width[row]
        v_ego = snap.vel[row]
        hd = np.array([np.cos(h), np.sin(h)])
        U, F = attraction(q_cand, target, p.k_att, p.d_att_m)
        ego_corners = footprint_corners(q_cand, np.full(C, h), np.full(C, L), np.full(C, W))  # (C,4,2)

        # other vehicles within the sensing radius
        o_pos, o_hd, o_len, o_wid, o_vel = obstacle_vehicles(obs, row, q_cand[0], p.sense_radius_m)
        v_safe = np.inf
        if len(o_pos):
            oc = footprint_corners(o_pos, o_hd, o_len, o_wid)
            O = len(o_pos)
            P = np.repeat(ego_corners, O, axis=0)
            Q = np.tile(oc, (C, 1, 1))
            rho, p_ego, p_obs = convex_distance(P, Q)
            centre_dir, _ = _unit(np.repeat(q_cand, O, axis=0) - np.tile(o_pos, (C, 1)))
            away, n = _unit(p_ego - p_obs)
            away = np.where((n > 1e-6)[:, None], away, centre_dir)
            towards = -away
            cos_phi = np.maximum(towards @ hd, 0.0)
            v_rel = v_ego[None, :] - np.tile(o_vel, (C, 1))
            closing = np.maximum(np.einsum("ij,ij->i", v_rel, towards), 0.0)
            rho0 = p.rho0_min_m + cos_phi * (closing**2 / (2 * p.rho0_decel_mps2) + p.rho0_headway_s * np.hypot(*v_ego))
            Ur, Fr = repulsion(rho, away, rho0, p.k_rep)
            U = U + Ur.reshape(C, O).sum(axis=1)
            F = F + Fr.reshape(C, O, 2).sum(axis=1)
            v_safe = self._governor(q_cand[0], hd, L, W, oc, o_vel)

        segs = self.road.segments_near(q_cand[0], p.rho0_edge_m + 0.5 * np.hypot(L, W) + 5.0)
        if len(segs):
            S = len(segs)
            P = np.repeat(ego_corners, S, axis=0)
            Q = np.tile(segs, (C, 1, 1))
            rho, _, _ = convex_distance(P, Q)
            _, closest = point_segment_distance(q_cand, segs[:, 0], segs[:, 1])  # (C,S,2)
            away, _ = _unit(q_cand[:, None, :] - closest)
            away = away.reshape(-1, 2)
            # a car drifting towards the kerb feels it earlier: closing speed -> stopping distance
            closing = np.maximum(-(away @ v_ego), 0.0)
            rho0 = p.rho0_edge_m + closing**2 / (2.0 * p.edge_lat_decel_mps2) + p.edge_reaction_s * closing
            Ur, Fr = repulsion(rho, away, rho0, p.k_edge, rho_floor=0.05)
            U = U + Ur.reshape(C, S).sum(axis=1)
            F = F + Fr.reshape(C, S, 2).sum(axis=1)
        return Field(U, F, float(v_safe))

    def _governor(self, q, hd, L, W, corners, vel) -> float:
        nd = np.array([-hd[1], hd[0]])
        rel = corners - q
        x = rel @ hd  # (O,4)
        y = rel @ nd
        half = 0.5 * W + self.p.gov_margin_m
        ahead = (y.max(axis=1) >= -half) & (y.min(axis=1) <= half) & (x.max(axis=1) > 0.5 * L)
        if not ahead.any():
            return np.inf
        gap = np.maximum(x[ahead].min(axis=1) - 0.5 * L, 0.0)
        v_lead = np.maximum(vel[ahead] @ hd, 0.0)
        free = np.maximum(gap - self.p.gov_standstill_m, 0.0)
        return float(np.sqrt(v_lead**2 + 2.0 * self.p.gov_decel_mps2 * free).min())

    def velocity(self, fld: Field, cruise: float) -> np.ndarray:
        F = fld.F[0]
        mag = np.hypot(*F)
        if mag < 1e-9:
            return np.zeros(2)
        f_max = self.p.k_att * self.p.d_att_m
        speed = min(cruise, mag * cruise / f_max, fld.v_safe)
        return F / mag * speed

    # --- one step --------------------------------------------------------------------------
    def act(self, obs: Observation) -> np.ndarray:
        out = np.zeros((len(obs.ego_ids), 2))
        snap = obs.snapshot
        for k, (vid, row) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            task = self.tasks[vid]
            q = snap.pos[row]
            target = self.target(task, obs, row)
            fld = self.field(obs, row, q[None, :], target)
            self.last_force[vid] = float(np.hypot(*fld.F[0]))
            out[k] = self.velocity(fld, task.cruise_speed_mps)
        return out

    def target(self, task: EgoTask, obs: Observation, row: int) -> np.ndarray:
        snap = obs.snapshot
        return self.carrot(task, snap.pos[row], float(np.hypot(*snap.vel[row])))
