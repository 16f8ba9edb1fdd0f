"""``formation``: leader-follower formation of connected vehicles (SPEC §3, seed 003).

The **leader** (the first of ``members``) drives to its goal along the goal-aware potential field
of SPEC §3 (:mod:`.field`):

    F = eta_at rho_g g  +  reshape_{alpha, beta}( sum over obstacles of F_re1 + F_re2 )

(F_re1 away from the obstacle, F_re2 towards the goal, both ~ rho_g^n; the reshaping F_p' = (1 + alpha)
F_p, F_q' = F_q + beta |F_re| in the vehicle frame slides the resultant round an obstacle). It moves
along F at ``leader_speed_mps``, slowing near its goal and while the followers lag behind. Values
(n = 1, alpha = -0.3, beta = +0.3) and why: docs/formation.md.

**Followers** hold slots of a shape (:func:`sumo_avoid.planning.formation_shape.slots`) at the leader's position,
turned by its heading low-passed with ``frame_tau_s``: command = the leader's velocity (V2V) +
``k_slot_ps`` x slot error + the same goal-aware repulsion + member repulsion, capped.

**Mode** (SPEC §3): gamma = W_max / W, W the nominal shape's width across the formation frame,
W_max the free width the obstacles the leader knows leave within [-depth, ``lookahead_m``] along it,
centred on the leader's line (:func:`.field.free_width`). kappa = 1 keeps the shape,
kappa = 2 scales it laterally to fit W_max with ``clear_m`` each side, kappa = 3 (gamma <= gamma_min,
from ``safe_gap_m``) breaks it up: each follower avoids on its own with a weak pull
(``k_slot_broken_ps``) to its nominal slot (``broken = "slots"``) or to the point j x ``spacing_m``
behind the leader on the leader's path (``"trail"``). A higher kappa at once, a lower one after
``relax_s``; docs/formation.md has the details and why.

**Safety shield** (:mod:`.shield`): every command passes a velocity barrier against the
obstacles, other vehicles and the other members, whatever the gains. **On a road** (no
``[arena]``) everything runs in the leader's route frame, the carriageway the walls
(:mod:`.road_frame`, :mod:`.lane_plan`).

Sensing (truth or radar) and V2V: the leader's obstacle list goes to every member; the details,
and what each member's shield also sees, in docs/formation.md.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.control.formation import field as ff
from sumo_avoid.control.formation import shield
from sumo_avoid.control.formation.lane_plan import LaneFormation
from sumo_avoid.control.formation.obstacle_lists import ObstacleLists
from sumo_avoid.control.formation.road_frame import RoadFrame
from sumo_avoid.control.formation.trail import LeaderTrail
from sumo_avoid.core.config import FieldError, field_doc
from sumo_avoid.core.geometry import (
    convex_distance,
    footprint_corners,
    unit_norm,
    wrap_angle,
)
from sumo_avoid.core.types import EgoTask, Keys, Needs, Observation
from sumo_avoid.planning.formation_shape import SHAPES, member_order, slots, to_world
from sumo_avoid.sensing.v2v import V2VParams


@dataclass(frozen=True)
class FormationParams:
    """``[controllers.formation]``. On a road with ``road = "lanes"`` every member drives the apf road
    field with the scenario's ``[controllers.apf]`` parameters (read from ``Context.params``; a
    context built without a scenario, as in unit tests, takes that table's defaults)."""

    shape: str = field_doc("triangle", doc="formation shape: triangle, line, column, v, diamond")
    spacing_m: float = field_doc(8.0, positive=True, doc="slot spacing (the seed's unit, scaled), m")
    apex_deg: float = field_doc(90.0, positive=True, doc="triangle / v apex angle at the leader, deg (90 = the seed's "
                                                         "coordinates; its '45 deg' is each side's angle to the heading)")
    members: tuple[str, ...] = field_doc((), doc="ego ids in slot order, leader first (default: the egos' ids in "
                                                 "natural order, e.g. f0, f1, ..., f10)")
    leader_speed_mps: float = field_doc(1.2, positive=True, doc="leader's speed (seed: 0.15 m/s, x 8 scale), m/s")
    follower_max_speed_mps: float = field_doc(3.0, positive=True, doc="followers' speed cap, m/s")
    eta_at: float = field_doc(0.02, positive=True, doc="attraction gain eta_at, 1/s")
    eta_re: float = field_doc(0.2, positive=True, doc="repulsion gain eta_re, m^(3-n)/s")
    n_goal: float = field_doc(1.0, positive=True, doc="exponent n of the goal-aware factor rho_g^n, 1")
    rho0_m: float = field_doc(10.0, positive=True, doc="obstacle influence distance rho0, m")
    rho_floor_m: float = field_doc(0.3, positive=True, doc="obstacle distance floor in the field, m")
    alpha: float = field_doc(-0.3, signed=True, doc="reshaping along the heading, F_p' = (1 + alpha) F_p, in (-1, 1)")
    beta: float = field_doc(0.3, signed=True, doc="reshaping across, F_q' = F_q + beta |F_re|, in (-1, 1)")
    max_turn_deg: float = field_doc(75.0, positive=True, doc="the leader's command stays within this angle of its "
                                                             "heading (a car turns while it moves), deg")
    slow_radius_m: float = field_doc(6.0, positive=True, doc="the leader slows down within this distance of the goal, m")
    k_slot_ps: float = field_doc(0.3, positive=True, doc="followers' slot gain (kappa 1, 2), 1/s")
    k_slot_broken_ps: float = field_doc(0.15, positive=True, doc="followers' gain to their trail point when broken up "
                                                                "(kappa 3), 1/s")
    k_member: float = field_doc(4.0, positive=True, doc="member-member repulsion gain, m^3/s")
    rho0_member_m: float = field_doc(3.0, positive=True, doc="member-member influence distance (footprint gap), m")
    frame_tau_s: float = field_doc(2.0, positive=True, doc="low-pass time constant of the formation frame's heading, s")
    wait_gain_pm: float = field_doc(0.1, doc="leader slows by this per metre of followers' RMS slot error, 1/m")
    wait_free_m: float = field_doc(2.0, doc="... beyond this RMS slot error, m")
    wait_min: float = field_doc(0.3, positive=True, doc="... down to this fraction of its speed, 1")
    carrot_m: float = field_doc(30.0, positive=True, doc="road: the leader aims this far ahead, across at the centre "
                                                        "of the free gap ahead, until its goal is nearer, m")
    lookahead_m: float = field_doc(25.0, positive=True, doc="W_max: obstacles up to this far ahead of the leader, m")
    window_m: float = field_doc(30.0, positive=True, doc="W_max: half width of the window across the heading, m")
    clear_m: float = field_doc(1.0, doc="kappa 2: clearance kept to the obstacles on each side, m")
    safe_gap_m: float = field_doc(2.0, doc="gamma_min: sideways gap neighbours keep, m")
    relax_s: float = field_doc(2.0, doc="a lower kappa is taken only after it held this long, s")
    widen_rate_ps: float = field_doc(0.1, positive=True, doc="the lateral scale grows at most this fast, 1/s")
    road: str = field_doc("lanes", doc="on a road: 'lanes' (slots held in whole lanes, each member driving the apf "
                                       "road field in its lane: control/formation/lane_plan.py) or 'field' (the arena's "
                                       "field and shield in the leader's route frame: control/formation/road_frame.py)")
    block_speed_frac: float = field_doc(0.5, doc="road 'lanes': a vehicle slower than this fraction of leader_speed_mps "
                                                  "blocks its lane for the formation, 1")
    goal_lane_m: float = field_doc(150.0, doc="road 'lanes': this near its goal the formation moves to the goal's lane, m")
    lost_window_s: float = field_doc(10.0, positive=True, doc="once the leader is at its goal, a follower that came less "
                                                             "than lost_progress_m nearer its own in this time ...")
    lost_progress_m: float = field_doc(1.0, doc="... follows the leader's path (a carrot spacing_m ahead on it) to its end, m")
    broken: str = field_doc("slots", doc="kappa 3: 'slots' (weak pull to the nominal slots, each avoids on its "
                                         "own) or 'trail' (each follows the leader's path)")
    behind: float = field_doc(1.0, doc="W_max also counts obstacles beside the formation's rows: this fraction "
                                       "of its depth behind the leader, 1")
    shield_slide: float = field_doc(0.0, doc="safety shield: a correction also slides along the hazard, this "
                                             "fraction of it, to the left (arena; no road), 1")
    predict_s: float = field_doc(0.0, doc="truth: other vehicles count as the (still) box they sweep in this time, s")
    sense_radius_m: float = field_doc(40.0, positive=True, doc="truth: the leader knows obstacles within this range, m")
    shield_k_ps: float = field_doc(0.5, positive=True, doc="safety shield: approach speed to a hazard at most this "
                                                          "times the free distance beyond the margin, 1/s")
    shield_members: str = field_doc("disc", doc="safety shield: members against each other as 'disc' (the disc "
                                                "of the half diagonal, safe at any heading: a slow member's heading "
                                                "can swing round in a step with the relaxation actuator) or "
                                                "'footprint' (cars: bounded yaw rate; lane-wide slots on a road)")
    shield_margin_m: float = field_doc(0.3, doc="safety shield: free distance kept to obstacles (disc of the half "
                                                "diagonal) and vehicles (footprints), m")
    v2v_gate_m: float = field_doc(4.0, positive=True, doc="radar: a return this close to a member's V2V position "
                                                          "is that member and is dropped, m")
    delay_s: float = field_doc(0.0, doc="V2V: members' states arrive this late, s")
    pos_noise_m: float = field_doc(0.0, doc="V2V: std of Gaussian noise on members' positions, m")
    vel_noise_mps: float = field_doc(0.0, doc="V2V: std of Gaussian noise on members' velocities, m/s")

    def __post_init__(self):
        if self.shield_members not in ("disc", "footprint"):
            raise FieldError("shield_members", "'disc' or 'footprint'", self.shield_members)
        if self.road not in ("lanes", "field"):
            raise FieldError("road", "'lanes' or 'field'", self.road)
        if self.broken not in ("slots", "trail"):
            raise FieldError("broken", "'slots' or 'trail'", self.broken)
        if self.shape not in SHAPES:
            raise FieldError("shape", f"one of {list(SHAPES)}", self.shape)
        for k in ("alpha", "beta"):
            if not -1.0 < getattr(self, k) < 1.0:
                raise FieldError(k, "a number in (-1, 1)", getattr(self, k))


def forward_cone(v, heading: float, max_turn: float) -> np.ndarray:
    """A car cannot turn on the spot: a command more than ``max_turn`` (rad) off the heading is
    turned to ``heading +- max_turn`` (towards it), keeping its speed, so the car turns while it
    moves instead of stopping with its wheels unable to turn it."""
    off = float(wrap_angle(np.arctan2(v[1], v[0]) - heading))
    if abs(off) <= max_turn:
        return v
    a = heading + np.sign(off) * max_turn
    return float(np.hypot(*v)) * np.array([np.cos(a), np.sin(a)])


class FormationController(BaseController):
    """Leader-follower formation with the goal-aware field, width ratio gamma and modes kappa (SPEC §3)."""

    needs = Needs(goals=True, v2v=True)
    metrics = ("formation",)  # S_ef and its terms, kappa shares (sumo_avoid.metrics.formation_score)
    plots = ("formation",)  # formation.png: paths and kappa over time (sumo_avoid.plots.PLOTS)
    stats_keys = Keys(("formation_min_gamma",), nested=("formation_kappa_steps", "formation_mode_log"))  # stats()

    def __init__(self, params: FormationParams, ctx):
        super().__init__(params, ctx)
        self.step_s = float(ctx.step_s)
        self.sensing = ObstacleLists(params, tuple(ctx.obstacles))  # what the members know
        # on a road (no [arena]) the formation drives in the leader's route frame (road_frame.py, lane_plan.py)
        self._on_road, self.road = getattr(ctx, "road", None) is not None and getattr(ctx, "walls", None) is None, None
        self.lanes = LaneFormation(params, ctx) if self._on_road and params.road == "lanes" else None
        self.order: list[str] = []
        self.offsets = np.zeros((0, 2))
        self.frame: float | None = None
        self.kappa, self.scale, self._lower_since = 1, 1.0, None
        self.kappa_steps = [0, 0, 0]
        self.log: list[list[float]] = []  # [time_s, kappa] at every change
        self.gamma_min_seen = np.inf
        self.trail = LeaderTrail(params)  # the leader's path
        self.last = {}  # the last step's gamma, W, W_max, gamma_min (tests, plots)

    def v2v_params(self) -> V2VParams:
        return V2VParams(self.p.delay_s, self.p.pos_noise_m, self.p.vel_noise_mps, 0.0, 0.1, 0.0)

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        if self.lanes is not None:
            self.lanes.add_ego(task)
        if not self.order or task.vid not in self.order:
            self.order = member_order(self.p, set(self.tasks) | set(self.order))
            self.offsets = slots(self.p.shape, len(self.order), self.p.spacing_m, self.p.apex_deg)

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        if self.lanes is not None:
            self.lanes.remove_ego(vid)

    def stats(self) -> dict:
        return {"formation_kappa_steps": list(self.kappa_steps), "formation_mode_log": self.log,
                "formation_min_gamma": float(self.gamma_min_seen) if np.isfinite(self.gamma_min_seen) else None}

    def _repulsion(self, pos, heading, length, width, goal, polys, mask) -> np.ndarray:
        """Goal-aware repulsion (E,2) of each ego from the obstacles it feels, before the reshaping."""
        p, E, O = self.p, len(pos), len(polys)
        if O == 0:
            return np.zeros((E, 2))
        ego = footprint_corners(pos, heading, length, width)
        rho, on_ego, on_obs = convex_distance(np.repeat(ego, O, axis=0), np.tile(polys, (E, 1, 1)))
        away, n = unit_norm(on_ego - on_obs)
        centre, _ = unit_norm(np.repeat(pos, O, axis=0) - np.tile(polys.mean(axis=1), (E, 1)))
        away = np.where((n > 1e-6)[:, None], away, centre)
        to_goal, rho_g = unit_norm(np.asarray(goal, float) - pos)
        rho = np.where(mask.ravel(), np.maximum(rho, p.rho_floor_m), np.inf)
        f1, f2 = ff.repulsion_terms(rho, away, np.repeat(rho_g, O), np.repeat(to_goal, O, axis=0),
                                    p.eta_re, p.rho0_m, p.n_goal)
        return (f1 + f2).reshape(E, O, 2).sum(axis=1)

    def _member_repulsion(self, own_pos, nb_pos, heading, length, width) -> np.ndarray:
        """(E,2) push of each member away from the others: footprint-to-footprint distance rho
        (own pose now against the others' V2V positions), k_member (1/rho - 1/rho0) / rho^2."""
        p, E = self.p, len(own_pos)
        if E < 2:
            return np.zeros((E, 2))
        i, j = np.nonzero(~np.eye(E, dtype=bool))
        a = footprint_corners(own_pos[i], heading[i], length[i], width[i])
        b = footprint_corners(nb_pos[j], heading[j], length[j], width[j])
        rho, on_a, on_b = convex_distance(a, b)
        away, n = unit_norm(on_a - on_b)
        centre, _ = unit_norm(own_pos[i] - nb_pos[j])
        away = np.where((n > 1e-6)[:, None], away, centre)
        rho = np.maximum(rho, p.rho_floor_m)
        k = np.where(rho <= p.rho0_member_m, 1.0 / rho - 1.0 / p.rho0_member_m, 0.0)
        f = (p.k_member * k / rho**2)[:, None] * away
        return np.column_stack([np.bincount(i, f[:, 0], E), np.bincount(i, f[:, 1], E)])

    def _shield(self, v, pos, heading, length, width, nb_pos, nb_vel, haz) -> np.ndarray:
        ego = shield.Members(pos, heading, length, width, nb_pos, nb_vel)
        walls = None if self.road is None else self.road.walls(pos, heading, length, width, self.p.shield_margin_m,
                                                                 self.p.shield_k_ps)
        return shield.apply(v, ego, *haz, self.p.shield_margin_m, self.p.shield_k_ps, walls, self.p.shield_slide,
                            self.p.shield_members == "disc")

    def _mode(self, lead_pos, goal, polys, lead_only, rel_lon, rel_lat, length, width, t) -> None:
        p = self.p
        c, s = np.cos(self.frame), np.sin(self.frame)
        span = float(np.ptp(self.offsets[:, 1]))
        W = ff.formation_width(self.offsets[:, 1], width)  # the nominal shape's: see the module doc
        depth = max(float(-self.offsets[:, 0].min()), float(-rel_lon.min())) + 0.5 * length  # nominal or strung out
        ahead = min(p.lookahead_m, float(np.hypot(*(goal - lead_pos))))
        if len(polys) and lead_only.any():
            rel = polys[lead_only] - lead_pos
            x, y = rel[..., 0] * c + rel[..., 1] * s, -rel[..., 0] * s + rel[..., 1] * c
            keep = (x.max(axis=1) >= -depth * p.behind) & (x.min(axis=1) <= ahead)
            iv = np.column_stack([y.min(axis=1), y.max(axis=1)])[keep]
        else:
            iv = np.zeros((0, 2))
        if self.road is not None:  # the corridor's bounds (the frame's heading is the road's, ~0)
            iv = np.vstack([iv, self.road.occupied(float(lead_pos[1]), depth * p.behind, ahead)])
        gap_lo, gap_hi, W_max = ff.free_gap(iv, p.window_m)
        gamma = W_max / W
        s_min = ff.min_lateral_scale(self.offsets, length, width, p.safe_gap_m)
        g_min = ff.gamma_min(s_min, span, width, p.clear_m, W)
        self._switch(ff.mode(gamma, g_min), t, gap_centre=0.5 * (gap_lo + gap_hi), gamma=gamma, W=W,
                     W_now=ff.formation_width(rel_lat, width), W_max=W_max, gamma_min=g_min)
        target = ff.lateral_scale(W_max, span, width, p.clear_m) if self.kappa == 2 else 1.0
        self.scale = min(target, self.scale + p.widen_rate_ps * self.step_s) if target > self.scale else target

    def _switch(self, want: int, t: float, **last) -> int:
        """Mode kappa with hysteresis (a higher one at once, a lower one after ``relax_s``), counted and
        logged; ``last`` (gamma, W, W_max, gamma_min, ...) kept for tests and plots."""
        if want >= self.kappa:
            self._lower_since = None
            if want > self.kappa:
                self.kappa = want
                self.log.append([float(t), want])
        else:
            self._lower_since = t if self._lower_since is None else self._lower_since
            if t - self._lower_since >= self.p.relax_s - 1e-9:
                self.kappa, self._lower_since = want, None
                self.log.append([float(t), want])
        self.kappa_steps[self.kappa - 1] += 1
        self.gamma_min_seen = min(self.gamma_min_seen, last["gamma"])
        self.last = {**last, "kappa": self.kappa}
        return self.kappa

    def act(self, obs: Observation) -> np.ndarray:
        ids, goals = obs.ego_ids, np.array([self.tasks[v].goal for v in obs.ego_ids], float).reshape(-1, 2)
        leader = self.order[0] if self.order else None
        if self.lanes is not None:
            _, _, nb_pos, nb_vel = obs.v2v.states(obs.snapshot, obs.ego_rows)
            t = obs.snapshot.time_s
            return self.lanes.act(obs, self.order, self.offsets, leader if leader in ids else None, nb_pos,
                                  nb_vel, lambda want, **last: self._switch(want, t, **last))
        if not self._on_road or (self.road is None and leader not in ids):
            return self._act(obs, goals)
        if self.road is None:
            self.road = RoadFrame(self.tasks[leader])
            self.sensing.set_static(self.road.polygons(self.sensing.static))
        lk = ids.index(leader) if leader in ids else None  # once the leader has left: the frame at a follower
        fobs = self.road.enter(obs, obs.ego_rows[0 if lk is None else lk])
        goals = self.road.to_frenet(goals, self.road.s_lead)
        if lk is not None:
            goals[lk] = self.road.carrot(fobs.snapshot.pos[obs.ego_rows[lk]], goals[lk], self.p.carrot_m,
                                         self.last.get("gap_centre", 0.0))
        return self.road.leave(fobs, self._act(fobs, goals))

    def _act(self, obs: Observation, goals) -> np.ndarray:
        p, snap = self.p, obs.snapshot
        ids, rows = obs.ego_ids, obs.ego_rows
        own_pos, own_vel, nb_pos, nb_vel = obs.v2v.states(snap, rows)
        heading, length, width = snap.heading[rows], snap.length[rows], snap.width[rows]
        leader = self.order[0] if self.order else None
        lk = ids.index(leader) if leader in ids else None
        if lk is None and len(self.trail.path) > 1:
            goals = self.trail.lost_goals(ids, own_pos, goals, snap.time_s)
        polys, mask, lead_only, static, hvel, smask = self.sensing.lists(obs, rows[lk] if lk is not None else None, nb_pos,
                                                                         self.order, self.road is not None)
        haz = (polys, smask, static, hvel)
        fmask = mask if self.road is None else self.road.field_mask(own_pos, length, width, polys, mask, lk, p.clear_m)
        rep = self._repulsion(own_pos, heading, length, width, goals, polys, fmask)
        rep_h = ff.reshape(rep, heading, p.alpha, p.beta)  # the leader's (and the followers' once it has left)
        out = np.zeros((len(ids), 2))
        member = self._member_repulsion(own_pos, nb_pos, heading, length, width)
        _, rho_g = unit_norm(goals - own_pos)
        field = ff.attraction(own_pos, goals, p.eta_at) + rep_h
        cruise = p.leader_speed_mps * np.minimum(1.0, rho_g / p.slow_radius_m)
        field_v = unit_norm(field)[0] * cruise[:, None]
        if lk is None:  # the leader is done: each follower drives the field to its own goal, reshaped in the
            # frame of the way to it (see the followers' reshaping below)
            to_goal = goals - own_pos
            f = ff.attraction(own_pos, goals, p.eta_at) + ff.reshape(rep, np.arctan2(to_goal[:, 1], to_goal[:, 0]),
                                                                     p.alpha, p.beta)
            v = unit_norm(f)[0] * cruise[:, None]
            v = np.array([forward_cone(f, h, np.radians(p.max_turn_deg)) for f, h in zip(v, heading)]) + member
            v = v * np.minimum(1.0, p.follower_max_speed_mps / np.maximum(np.hypot(*v.T), 1e-9))[:, None]
            return self._shield(v, own_pos, heading, length, width, nb_pos, nb_vel, haz)
        if self.frame is None:
            self.frame = float(heading[lk])
        # the frame turns with the leader's heading, low-passed, and only as fast as the leader moves
        # (a leader creeping round an obstacle must not swing the rear slots through each other)
        moving = min(1.0, float(np.hypot(*own_vel[lk])) / p.leader_speed_mps)
        a = (1.0 - np.exp(-self.step_s / p.frame_tau_s)) * moving
        self.frame = float(wrap_angle(self.frame + a * wrap_angle(heading[lk] - self.frame)))
        slot_of = {v: k for k, v in enumerate(self.order)}
        k_slot = np.array([slot_of[v] for v in ids])
        c, s = np.cos(self.frame), np.sin(self.frame)
        rel = own_pos - own_pos[lk]
        self._mode(own_pos[lk], goals[lk], polys, lead_only, rel[:, 0] * c + rel[:, 1] * s, -rel[:, 0] * s + rel[:, 1] * c,
                   float(length[lk]), float(width[lk]), snap.time_s)
        scale = self.scale if self.kappa == 2 else 1.0
        self.trail.extend(nb_pos[lk])
        if self.kappa == 3 and p.broken == "trail":
            slot_pos = self.trail.points(k_slot * p.spacing_m)
        else:
            slot_pos = to_world(self.offsets[k_slot], nb_pos[lk], self.frame, scale)
        err = slot_pos - own_pos
        fol = np.arange(len(ids)) != lk
        e_rms = float(np.sqrt((err[fol] ** 2).sum(axis=1).mean())) if fol.any() else 0.0
        wait = np.clip(1.0 - p.wait_gain_pm * max(e_rms - p.wait_free_m, 0.0), p.wait_min, 1.0)
        out[lk] = forward_cone(field_v[lk] * wait, heading[lk], np.radians(p.max_turn_deg))
        gain = p.k_slot_broken_ps if self.kappa == 3 else p.k_slot_ps
        # a follower's reshaping frame is the way its slot pulls it, not its heading: a slow member's heading
        # swings with every command (relaxation actuator), and the beta push with it, which can hold
        # followers in pockets between obstacles for good
        pull = nb_vel[lk] + gain * err
        v = pull + ff.reshape(rep, np.arctan2(pull[:, 1], pull[:, 0]), p.alpha, p.beta) + member
        v = v * np.minimum(1.0, p.follower_max_speed_mps / np.maximum(np.hypot(*v.T), 1e-9))[:, None]
        out[fol] = v[fol]
        return self._shield(out, own_pos, heading, length, width, nb_pos, nb_vel, haz)
