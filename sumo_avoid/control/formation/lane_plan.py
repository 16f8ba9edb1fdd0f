"""The formation on a road, lane by lane (SPEC §3 on SPEC §5's route frame; ``road = "lanes"``).

A car on a road drives in a lane, so on a road the formation's shape is held in lanes: each slot's
lateral offset is rounded to whole lanes (:func:`lane_units`; the diamond's side slots are one lane
right and left of the leader) and its offset along the road is kept as an arc-length gap behind the
leader in the leader's route frame. Every step:

1. **Free lanes** (:func:`blocked_lanes`): a lane of the leader's edge is blocked when, from
   ``depth`` behind the leader (the formation's rows) to ``lookahead_m`` ahead of it, a vehicle the
   leader senses (its sensor; members, known over V2V, left out) overlaps it and is slower than
   ``block_speed_frac`` x the leader's speed (a stopped car of a lane closure, a slow truck), or the
   carriageway's bounds cut into it (a lane that ends). :func:`free_run`: the run of adjacent free
   lanes with the leader's lane, else the widest one nearest to it.
2. **Width ratio and mode**: W = the lanes the shape spans x the lane width, W_max = the free run's
   width, gamma = W_max / W and gamma_min = 1 / (lanes spanned) (one lane: nothing to narrow to);
   kappa from :func:`~sumo_avoid.control.formation.field.mode` with the controller's hysteresis.
3. **Lanes of the slots** (:func:`assign_lanes`): kappa 1 keeps the shape's lanes about the leader's
   lane, moved sideways as little as needed to fit the free run (or the goal's lane within
   ``goal_lane_m`` of the goal); kappa 2 maps the shape's lanes linearly onto the fewer free lanes
   (narrowing); kappa 3 puts everyone in one lane, a column. Members that come to share a lane are
   strung out at least ``spacing_m`` apart in slot order.
4. **Driving**: every member drives the ``apf`` road field (:mod:`sumo_avoid.control.apf.apf`, with the
   scenario's ``[controllers.apf]``: lane keeping, repulsion
   from vehicles and the road's bounds, the speed governor behind what is ahead, the speed for
   bends) towards the centre of its lane; the leader at ``leader_speed_mps`` (slowed while the
   followers lag, ``wait_*``), a follower at the leader's speed along the road plus ``k_slot_ps`` x
   its gap error (at most ``follower_max_speed_mps``). A member changes lanes one lane at a time, and
   only when the target lane is free beside it (:func:`lane_is_free`; with radar on what every member
   sees, pooled over V2V, and the members' own positions); otherwise it keeps its lane.
   Once the leader has reached its goal, each follower drives to its own goal.
"""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.control.formation import field as ff
from sumo_avoid.control.apf.apf import ApfDriver, ApfParams
from sumo_avoid.road.gaps import LANE_OVERLAP_M, lane_is_free
from sumo_avoid.core.geometry import near_any
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.sensing.perception import ASSUMED_WIDTH_M, perceived_boxes

#: A radar return's assumed box (sensing.perception: car-sized, the return on its near side) is in a
#: lane when it overlaps it by more than this, its half width (core.gaps.LANE_OVERLAP_M for true
#: footprints): a car-sized box stands for a vehicle of unknown width (a box pushed back along the
#: line of sight, e.g. a truck's, can reach into the next lane and block two lanes).
RADAR_OVERLAP_M = 0.5 * ASSUMED_WIDTH_M
#: A lane whose edges the carriageway's bounds cut by more than this is closed, m.
BOUND_TOL_M = 0.3


def lane_units(across_m: np.ndarray, lane_width_m: float) -> np.ndarray:
    """(M,) whole lanes of the slots' lateral offsets (m, left > 0): round(y / lane width)."""
    return np.rint(np.asarray(across_m, float) / lane_width_m).astype(int)


def blocked_lanes(centres, widths, bounds, obstacles, s_lead: float, behind_m: float, ahead_m: float,
                  slow_mps: float, overlap_m: float = LANE_OVERLAP_M) -> np.ndarray:
    """(K,) which of the K lanes (centres, widths (K,) at the leader, m) are blocked between
    ``s_lead - behind_m`` and ``s_lead + ahead_m``: by an obstacle (s, d, length, width, speed along
    the road: (O, 5)) overlapping it by more than ``overlap_m`` and slower than ``slow_mps``, or by
    the carriageway's bounds ((lo, hi) (N,) sampled over that stretch) cutting into it."""
    c, w = np.asarray(centres, float), np.asarray(widths, float)
    lo, hi = (np.asarray(b, float) for b in bounds)
    out = (c - 0.5 * w < lo.max() - BOUND_TOL_M) | (c + 0.5 * w > hi.min() + BOUND_TOL_M)
    o = np.asarray(obstacles, float).reshape(-1, 5)
    near = (o[:, 0] + 0.5 * o[:, 2] >= s_lead - behind_m) & (o[:, 0] - 0.5 * o[:, 2] <= s_lead + ahead_m)
    o = o[near & (o[:, 4] < slow_mps)]
    if len(o):
        overlap = np.minimum(c[None] + 0.5 * w[None], o[:, 1:2] + 0.5 * o[:, 3:4]) \
            - np.maximum(c[None] - 0.5 * w[None], o[:, 1:2] - 0.5 * o[:, 3:4])
        out |= (overlap > overlap_m).any(axis=0)
    return out


def free_run(blocked: np.ndarray, lane: int) -> tuple[int, int] | None:
    """(a, b): the run of adjacent free lanes a..b holding ``lane``, else the widest run, the nearest
    to ``lane`` among equals; None if every lane is blocked."""
    runs, a = [], None
    for k, b in enumerate(list(blocked) + [True]):
        if not b and a is None:
            a = k
        elif b and a is not None:
            runs.append((a, k - 1))
            a = None
    if not runs:
        return None
    for r in runs:
        if r[0] <= lane <= r[1]:
            return r
    return max(runs, key=lambda r: (r[1] - r[0], -min(abs(lane - r[0]), abs(lane - r[1]))))


def gamma_of(run: tuple[int, int] | None, lanes_spanned: int) -> tuple[float, float]:
    """(gamma, gamma_min) in whole lanes: free lanes / lanes the shape spans, and 1 / lanes spanned."""
    free = 0 if run is None else run[1] - run[0] + 1
    return free / lanes_spanned, 1.0 / lanes_spanned


def assign_lanes(units: np.ndarray, along_m: np.ndarray, kappa: int, run: tuple[int, int], lead_lane: int,
                 prefer_lane: int, spacing_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(lanes (M,), gaps along the road (M,), m, <= 0) of the slots (``units`` whole lanes and
    ``along_m`` behind the leader, slot 0 the leader) for mode ``kappa`` in the free run (a, b).

    kappa 1: the leader's lane c is the one nearest ``prefer_lane`` for which c + units fits in the
    run (the run's own lanes if the shape is wider: then kappa is not 1); kappa 2: the shape's lanes
    mapped linearly onto the run, ties towards ``lead_lane``; kappa 3: every slot in the run's lane
    nearest ``lead_lane``. Then slots sharing a lane keep at least ``spacing_m`` between them, in
    slot order along the road (the leader's first)."""
    u, along = np.asarray(units, int), np.asarray(along_m, float).copy()
    a, b = run
    lo, hi = int(u.min()), int(u.max())
    if kappa == 1 and b - a >= hi - lo:
        c = min(max(prefer_lane, a - lo), b - hi)
        lanes = c + u
    elif kappa == 3 or b == a or hi == lo:
        lanes = np.full(len(u), min(max(lead_lane, a), b))
    else:
        x = a + (u - lo) * (b - a) / (hi - lo)
        lanes = np.floor(x + 0.5 - 1e-9 * np.sign(x - lead_lane)).astype(int)  # ties towards the leader's lane
        lanes[0] = min(max(lanes[0], a), b)
    order = sorted(range(len(u)), key=lambda k: (-along[k], k))
    last: dict[int, float] = {}
    for k in order:
        ln = int(lanes[k])
        if ln in last:
            along[k] = min(along[k], last[ln] - spacing_m)
        last[ln] = along[k]
    return lanes.astype(int), along


def near_members(o_pos, member_sd, gate_m: float) -> np.ndarray:
    """(O,) which vehicles at ``o_pos`` (O, 2) are members: within ``gate_m`` of a member's V2V position
    ``member_sd`` (M, 2), both in one route frame (members the frame does not reach left out)."""
    q = np.asarray(member_sd, float).reshape(-1, 2)
    return near_any(o_pos, q[np.isfinite(q).all(axis=1)], gate_m)


def in_frame(view, s_hint: float, xy, window_m: float) -> np.ndarray:
    """(N, 2) world points ``xy`` as (s, d from the route's reference line) in ``view``'s frame
    (NaN where the frame does not reach them within ``window_m`` of ``s_hint``)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    s, d = view.frame.to_frenet(xy, np.full(len(xy), s_hint), window_m)
    return np.column_stack([s, d - view.line.offset(s)])


class LaneFormation:
    """The members' road driving for :class:`~sumo_avoid.control.formation.formation.FormationController`:
    every member drives the apf road field with the scenario's ``[controllers.apf]`` parameters
    (``ctx.params``; a context built without a scenario, as in unit tests, has none: then
    ``ApfParams()``, the defaults of that table)."""

    def __init__(self, p, ctx):
        self.p = p
        self.driver = ApfDriver(ctx.params.get("controllers.apf", ApfParams()), ctx)
        self.lane_of: dict[str, int] = {}
        self._pool = (None, None)  # (the observation, every member's radar returns pooled): once a step

    def add_ego(self, task: EgoTask) -> None:
        self.driver.add_ego(task)

    def remove_ego(self, vid: str) -> None:
        self.driver.remove_ego(vid)
        self.lane_of.pop(vid, None)

    # --- the plan -------------------------------------------------------------------------------
    def plan(self, obs: Observation, order, offsets, lead: str, member_xy, switch):
        """Lanes and gaps of every slot this step: (lane by id, gap along by id, leader's s, the s of
        each member of ``obs.ego_ids`` (V2V positions ``member_xy``, aligned) in the leader's frame);
        ``switch(want, gamma=, gamma_min=, W=, W_max=)`` -> kappa applies the controller's hysteresis
        and records the mode."""
        p, view = self.p, self.driver.views[lead]
        row = obs.ego_rows[obs.ego_ids.index(lead)]
        sc = self.driver.scene(obs, row, lead)
        _, centres = view.lanes.centres(sc.s)
        centres = centres - view.line.offset(np.array([sc.s]))[0]
        widths = np.asarray(view.lanes.centres(sc.s)[0].widths_m, float)
        lane_w = float(np.mean(widths))
        units = lane_units(offsets[:, 1], lane_w)
        depth = float(-offsets[:, 0].min()) + 0.5 * sc.length
        member_sd = in_frame(view, sc.s, member_xy, 300.0)
        keep = ~near_members(sc.o_pos, member_sd, p.v2v_gate_m)  # members are known over V2V, not obstacles
        o = np.column_stack([sc.o_pos, sc.o_length, sc.o_width, sc.o_vel[:, 0]])[keep]
        s_grid = np.linspace(sc.s - depth, sc.s + p.lookahead_m, 25)
        blocked = blocked_lanes(centres, widths, view.corridor(s_grid), o, sc.s, depth, p.lookahead_m,
                                p.block_speed_frac * p.leader_speed_mps,
                                LANE_OVERLAP_M if obs.detections is None else RADAR_OVERLAP_M)
        lead_lane = int(np.argmin(np.abs(centres - sc.d)))
        run = free_run(blocked, lead_lane)
        spanned = int(units.max() - units.min()) + 1
        gamma, g_min = gamma_of(run, spanned)
        kappa = switch(ff.mode(gamma, g_min), gamma=gamma, gamma_min=g_min, W=spanned * lane_w,
                       W_max=gamma * spanned * lane_w)
        s_of = dict(zip(obs.ego_ids, member_sd[:, 0]))
        if run is None:  # nothing free ahead: everyone keeps its lane and the governors stop them
            lanes = {v: self.lane_of.get(v, lead_lane) for v in order}
            return lanes, dict(zip(order, offsets[:, 0])), sc.s, s_of
        goal_s, goal_d = view.goal
        prefer = int(np.argmin(np.abs(centres - goal_d))) if goal_s - sc.s <= p.goal_lane_m else lead_lane
        if kappa == 1 and prefer == lead_lane:
            prefer = self._kept_centre(lead, units, run, lead_lane)
        ln, along = assign_lanes(units, offsets[:, 0], kappa, run, lead_lane, prefer, p.spacing_m)
        return dict(zip(order, ln)), dict(zip(order, along)), sc.s, s_of

    def _kept_centre(self, lead: str, units, run, lead_lane: int) -> int:
        """kappa 1 away from the goal: the leader's lane of last step while the shape fits there."""
        c = self.lane_of.get(lead, lead_lane)
        return c if run[0] <= c + units.min() and c + units.max() <= run[1] else lead_lane

    # --- driving --------------------------------------------------------------------------------
    def _beside(self, obs: Observation, vid: str, sc, view, known):
        """What member ``vid`` knows of the lanes beside it for a lane change, in its frame: (pos (s, d),
        length, width, speed along the road). Ground truth: its scene. Radar: a front radar does not see
        a car alongside, so every member's
        returns are pooled (cooperative perception over V2V: a member behind sees the car beside one
        ahead), minus those within ``v2v_gate_m`` of a member, plus the members themselves (V2V)."""
        ids, xy, vel = known
        other = np.array([i != vid for i in ids])
        if obs.detections is None:  # its scene, fellow members marked
            member = near_members(sc.o_pos, in_frame(view, sc.s, xy[other], 200.0), self.p.v2v_gate_m)
            return sc.o_pos, sc.o_length, sc.o_width, sc.o_vel[:, 0], member
        pos, ln, wd, v = self._pooled(obs, xy)
        snap = obs.snapshot
        rows = [obs.ego_rows[obs.ego_ids.index(i)] for i in ids]
        member = np.concatenate([np.zeros(len(pos), bool), np.ones(int(other.sum()), bool)])
        pos = np.vstack([pos, xy[other]])
        ln = np.concatenate([ln, snap.length[rows][other]])
        wd = np.concatenate([wd, snap.width[rows][other]])
        v = np.vstack([v, vel[other]])
        if not len(pos):
            return np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0, bool)
        s, d = view.frame.to_frenet(pos, np.full(len(pos), sc.s), 200.0)
        ok = np.isfinite(s)
        s, d, ln, wd, v, member = s[ok], d[ok], ln[ok], wd[ok], v[ok], member[ok]
        vs, _ = view.frame.velocity_to_frenet(s, d, v)
        return np.column_stack([s, d - view.line.offset(s)]), ln, wd, vs, member

    def _pooled(self, obs: Observation, xy):
        """Every member's radar returns as assumed boxes (world pos, length, width, velocity), minus
        those within ``v2v_gate_m`` of a member's V2V position ``xy``: the same for every member, so
        built once per observation."""
        if self._pool[0] is not obs:
            parts = [perceived_boxes(d) for d in obs.detections]
            pos, _, ln, wd, v = (np.concatenate([b[i] for b in parts]) for i in range(5))
            keep = ~near_any(pos, xy, self.p.v2v_gate_m) if len(pos) else np.zeros(0, bool)
            self._pool = (obs, (pos[keep], ln[keep], wd[keep], v[keep]))
        return self._pool[1]

    def drive(self, obs: Observation, vid: str, want_lane: int, cruise: float, known) -> np.ndarray:
        """(2,) world velocity of member ``vid`` driving the road field towards the centre of its
        lane (one lane nearer ``want_lane`` when that lane is free beside it, :meth:`_beside`) at
        ``cruise``; ``known`` = (member ids, V2V positions, V2V velocities)."""
        drv, view = self.driver, self.driver.views[vid]
        row = obs.ego_rows[obs.ego_ids.index(vid)]
        sc = drv.scene(obs, row, vid)
        piece, centres = view.lanes.centres(sc.s)
        centres = centres - view.line.offset(np.array([sc.s]))[0]
        now = int(np.argmin(np.abs(centres - sc.d)))
        cur = self.lane_of.get(vid, now)
        cur = min(cur, len(centres) - 1)
        want = min(max(int(want_lane), 0), len(centres) - 1)
        if want != cur:
            nxt = cur + int(np.sign(want - cur))
            half = 0.5 * float(piece.widths_m[min(nxt, len(piece.widths_m) - 1)])
            speed = float(sc.vel[0])
            pos, ln, wd, vs, member = self._beside(obs, vid, sc, view, known)
            if lane_is_free(sc.s, speed, sc.length, pos, ln, wd, vs, (centres[nxt] - half, centres[nxt] + half), member):
                cur = nxt
        self.lane_of[vid] = cur
        ahead = drv.lookahead(math.hypot(*sc.vel))
        goal_s = view.goal[0]
        target = np.array([goal_s if goal_s - sc.s <= ahead else min(sc.s + ahead, view.length_m), centres[cur]])
        fld = drv.field(sc, sc.q[None, :], target)
        v = drv.velocity(fld, cruise, drv.road_speed(view, sc))
        return view.to_xy_velocity(sc.s, sc.d, v, drv.step_s)

    def act(self, obs: Observation, order, offsets, lead: str | None, member_xy, member_vel, switch) -> np.ndarray:
        """(E, 2) commands of the members in ``obs.ego_ids`` (V2V positions ``member_xy`` and velocities
        ``member_vel`` aligned with them; see the module doc)."""
        p, ids = self.p, obs.ego_ids
        out = np.zeros((len(ids), 2))
        known = (list(ids), np.asarray(member_xy, float).reshape(-1, 2), np.asarray(member_vel, float).reshape(-1, 2))
        if lead is None:  # the leader is at its goal: each follower to its own, in the goal's lane
            for k, vid in enumerate(ids):
                view = self.driver.views[vid]
                centres = view.lane_centres(view.goal[0])
                out[k] = self.drive(obs, vid, int(np.argmin(np.abs(centres - view.goal[1]))), p.leader_speed_mps, known)
            return out
        lanes, along, s_lead, s_of = self.plan(obs, order, offsets, lead, member_xy, switch)
        err = np.array([s_lead + along[v] - s_of[v] for v in ids if v != lead])
        e_rms = float(np.sqrt((err**2).mean())) if len(err) else 0.0
        wait = float(np.clip(1.0 - p.wait_gain_pm * max(e_rms - p.wait_free_m, 0.0), p.wait_min, 1.0))
        v_lead = float(np.hypot(*known[2][ids.index(lead)]))
        for k, vid in enumerate(ids):
            if vid == lead:
                cruise = p.leader_speed_mps * wait
            else:
                cruise = float(np.clip(v_lead + p.k_slot_ps * (s_lead + along[vid] - s_of[vid]), 0.0,
                                       p.follower_max_speed_mps))
            out[k] = self.drive(obs, vid, lanes[vid], cruise, known)
        return out
