"""``apf_sa``: the potential field of :mod:`.apf` plus simulated-annealing escape (SPEC §2, seed
001 §2.2, Fig. 2).

Trap detector (documented choice): an ego is *trapped* when, over the last ``trap_window_s``, it
advanced along its route less than ``trap_progress_frac * cruise * window`` **and** right now
either the force has almost vanished (``|F| < trap_force_frac * F_att_max``, the field's local
minimum) or the speed governor holds it below cruise (an obstacle it cannot pass sits in its
corridor). Both together: a car slowed in a bend is not trapped, a car queued behind a stopped
obstacle is.

Simulated annealing (seed Fig. 2) on the field frozen at that instant: from x = the ego's centre,
draw x1 = x + step (cos a, sin a) with a uniform; positions whose footprint leaves the drivable
area are refused; Delta = U(x1) - U(x); accept when Delta <= 0 or exp(-Delta/T) > u (u uniform);
cool T <- T * ``sa_cooling`` after each draw; stop when the walk is at least ``sa_escape_m`` from
the trap with a potential below the trap's (it has left the basin), or after ``sa_max_iter``
draws (then no escape this time). A car cannot jump to x1, so the walk's end point becomes an
*escape target*: the ego follows the reference path shifted sideways by the end point's lateral
offset (e.g. the free lane) until it has held that offset for ``escape_hold_s`` or
``escape_timeout_s`` has passed; then plain APF resumes.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from sumo_avoid.control.apf import ApfController, ApfParams
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.geometry import footprint_corners, point_segment_distance
from sumo_avoid.core.polyline import polyline_project, polyline_tangent
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.sensing.perception import obstacle_vehicles


@dataclass(frozen=True)
class ApfSaParams(ApfParams):
    trap_window_s: float = field_doc(2.0, doc="progress is judged over this window, s")
    trap_progress_frac: float = field_doc(0.7, doc="trapped below this fraction of cruise progress")
    trap_force_frac: float = field_doc(0.05, doc="|F| below this fraction of F_att_max = a minimum")
    sa_step_m: float = field_doc(1.0, doc="SA step length, m")
    sa_t0: float = field_doc(10.0, doc="SA initial temperature (potential units)")
    sa_cooling: float = field_doc(0.995, doc="SA cooling factor per draw (geometric schedule)")
    sa_max_iter: int = field_doc(1000, doc="SA draws per escape search (seed: 1000)")
    sa_escape_m: float = field_doc(3.0, doc="the walk has left the minimum this far from the trap, m")
    sa_free_ahead_m: float = field_doc(20.0, doc="the walk has left the basin where this much is free ahead along the route, m")
    escape_hold_s: float = field_doc(3.0, doc="keep the escape offset this long once reached, s")
    escape_timeout_s: float = field_doc(10.0, doc="give up an escape after this long, s")
    escape_room_m: float = field_doc(12.0, doc="when blocked, back up until this much room is free ahead, m")
    escape_reverse_speed_mps: float = field_doc(1.5, doc="speed while backing up, m/s")
    escape_margin_m: float = field_doc(0.5, doc="the escape target keeps the car this far from road edges, m")


@dataclass
class _EgoState:
    history: deque  # (time_s, arc length s_m)
    escape_offset: float | None = None
    escape_start_s: float = 0.0
    held_since_s: float | None = None
    cooldown_until_s: float = -math.inf
    reversing: bool = False


class ApfSaController(ApfController):
    params_cls = ApfSaParams

    def __init__(self, params: ApfSaParams, ctx):
        super().__init__(params, ctx)
        self.state: dict[str, _EgoState] = {}
        self.escapes = 0
        self.failed_searches = 0

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        self.state[task.vid] = _EgoState(deque())

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        self.state.pop(vid, None)

    def stats(self) -> dict:
        return {"sa_escapes": self.escapes, "sa_failed_searches": self.failed_searches}

    def _lateral(self, task: EgoTask, q) -> float:
        _, a, t = polyline_tangent(task.path, q)
        d = np.asarray(q) - a
        return float(t[0] * d[1] - t[1] * d[0])  # 2-D cross product: left of the path > 0

    def act(self, obs: Observation) -> np.ndarray:
        p = self.p
        snap = obs.snapshot
        out = np.zeros((len(obs.ego_ids), 2))
        f_max = p.k_att * p.d_att_m
        for k, (vid, row) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            task, st = self.tasks[vid], self.state[vid]
            q = snap.pos[row]
            speed = float(np.hypot(*snap.vel[row]))
            t = snap.time_s
            if st.escape_offset is not None:
                self._update_escape(task, st, q, t)
            st.history.append((t, polyline_project(task.path, q)))
            while st.history and st.history[0][0] < t - p.trap_window_s - 1e-9:
                st.history.popleft()
            offset = st.escape_offset or 0.0
            target = self.carrot(task, q, speed, offset)
            fld = self.field(obs, row, q[None, :], target)
            force = float(np.hypot(*fld.F[0]))

            window_full = st.history[-1][0] - st.history[0][0] >= p.trap_window_s - 1e-9
            progress = st.history[-1][1] - st.history[0][1]
            slow = progress < p.trap_progress_frac * task.cruise_speed_mps * p.trap_window_s
            stuck_now = (force < p.trap_force_frac * f_max or fld.v_safe < 0.9 * task.cruise_speed_mps
                         or speed < 0.5)
            if (st.escape_offset is None and window_full and slow and stuck_now and t >= st.cooldown_until_s):
                end = self._anneal(obs, row, target, float(fld.U[0]))
                if end is None:
                    self.failed_searches += 1
                    st.cooldown_until_s = t + p.trap_window_s
                else:
                    self.escapes += 1
                    st.escape_offset = self._inside_offset(task, q, speed, self._lateral(task, end),
                                                           float(snap.width[row]))
                    st.escape_start_s, st.held_since_s = t, None
                    target = self.carrot(task, q, speed, st.escape_offset)
                    fld = self.field(obs, row, q[None, :], target)
            out[k] = self.velocity(fld, task.cruise_speed_mps)
            if st.escape_offset is not None:
                out[k] = self._make_room(st, obs, row, out[k], fld.v_safe, target)
        return out

    def _inside_offset(self, task: EgoTask, q, speed: float, offset: float, width: float) -> float:
        """Shrink a lateral offset until the shifted carrot lies on the road with
        ``escape_margin_m`` to spare on each side of the car (a target on the kerb is no target)."""
        need = 0.5 * width + self.p.escape_margin_m
        for k in range(int(abs(offset) / 0.25) + 1):
            o = math.copysign(max(abs(offset) - 0.25 * k, 0.0), offset)
            c = self.carrot(task, q, speed, o)
            if self.road.outside_distance(c[None, :])[0] == 0.0 and self._clearance(c) >= need:
                return o
        return 0.0

    def _clearance(self, point) -> float:
        segs = self.road.segments_near(point, 10.0)
        if not len(segs):
            return math.inf
        d, _ = point_segment_distance(np.asarray(point)[None, :], segs[:, 0], segs[:, 1])
        return float(d.min())

    def _make_room(self, st: _EgoState, obs: Observation, row: int, v_des, v_safe: float, target):
        """A car cannot step sideways: when the escape is blocked straight ahead (the governor allows
        no speed) it backs up along its heading until ``escape_room_m`` is free on the line towards
        the escape target, then drives the escape forward. Needs ``actuator.max_reverse_speed_mps > 0``."""
        snap = obs.snapshot
        h = snap.heading[row]
        fwd = np.array([math.cos(h), math.sin(h)])
        if not st.reversing and v_safe < 0.5 and float(np.hypot(*snap.vel[row])) < 0.3:
            st.reversing = True
        if st.reversing:  # back up until the straight line towards the escape target is free
            aim = np.asarray(target) - snap.pos[row]
            room = self._room_ahead(obs, row, heading=math.atan2(aim[1], aim[0]))
            if room >= self.p.escape_room_m:
                st.reversing = False
                return v_des
            # back up against the route direction, so the nose straightens while the lateral
            # offset already won is kept (a three-point manoeuvre rather than undoing the turn)
            _, _, tangent = polyline_tangent(self.tasks[snap.ids[row]].path, snap.pos[row])
            back = -tangent if float(tangent @ fwd) > 0.0 else -fwd
            return self.p.escape_reverse_speed_mps * back
        return v_des

    def _room_ahead(self, obs: Observation, row: int, at=None, heading=None) -> float:
        """Free length ahead of the ego's footprint (placed at ``at`` with ``heading``), m."""
        snap = obs.snapshot
        h = snap.heading[row] if heading is None else heading
        pos = snap.pos[row] if at is None else at
        # what the ego perceives (radar + tracker when the sensor is on, else ground truth)
        o_pos, o_hd, o_len, o_wid, _ = obstacle_vehicles(obs, row, snap.pos[row], self.p.sense_radius_m)
        if not len(o_pos):
            return math.inf
        hd = np.array([math.cos(h), math.sin(h)])
        oc = footprint_corners(o_pos, o_hd, o_len, o_wid)
        rel = oc - pos
        x, y = rel @ hd, rel @ np.array([-hd[1], hd[0]])
        half = 0.5 * snap.width[row] + self.p.gov_margin_m
        ahead = (y.max(axis=1) >= -half) & (y.min(axis=1) <= half) & (x.max(axis=1) > 0)
        if not ahead.any():
            return math.inf
        return float(max(x[ahead].min(), 0.0) - 0.5 * snap.length[row])

    def _update_escape(self, task: EgoTask, st: _EgoState, q, t: float) -> None:
        p = self.p
        if abs(self._lateral(task, q) - st.escape_offset) < 1.0:
            st.held_since_s = t if st.held_since_s is None else st.held_since_s
        if (t - st.escape_start_s >= p.escape_timeout_s
                or (st.held_since_s is not None and t - st.held_since_s >= p.escape_hold_s)):
            st.escape_offset, st.held_since_s, st.reversing = None, None, False
            st.history.clear()
            st.cooldown_until_s = t + p.trap_window_s

    def _anneal(self, obs: Observation, row: int, target, U0: float):
        """Seed Fig. 2 on the frozen field; returns the escape point or None."""
        p, snap, rng = self.p, obs.snapshot, self.rng
        x0 = snap.pos[row].copy()
        # candidate footprints are aligned with the route (where the car would end up driving),
        # not with its momentary heading, which may point at the kerb after a manoeuvre
        _, _, t = polyline_tangent(self.tasks[snap.ids[row]].path, x0)
        h, L, W = math.atan2(t[1], t[0]), snap.length[row], snap.width[row]
        U0 = float(self.field(obs, row, x0[None, :], target, heading=h).U[0])
        x, Ux, T = x0.copy(), U0, p.sa_t0
        for _ in range(p.sa_max_iter):
            a = rng.uniform(0.0, 2.0 * math.pi)
            x1 = x + p.sa_step_m * np.array([math.cos(a), math.sin(a)])
            corners = footprint_corners(x1[None, :], np.array([h]), np.array([L]), np.array([W]))
            if self.road.footprint_outside_distance(corners)[0] > 0.0:
                T *= p.sa_cooling
                continue
            U1 = float(self.field(obs, row, x1[None, :], target, heading=h).U[0])
            delta = U1 - Ux
            if delta <= 0.0 or math.exp(-delta / max(T, 1e-12)) > rng.uniform():
                x, Ux = x1, U1
            T *= p.sa_cooling
            if Ux < U0 and np.hypot(*(x - x0)) >= p.sa_escape_m and self._leaves_basin(obs, row, x):
                return x
        return None

    def _leaves_basin(self, obs: Observation, row: int, x) -> bool:
        """Has the walk left the trap's basin? A footprint at x, aligned with the route, must have
        ``sa_free_ahead_m`` free in front of it (so the point is not just the next pocket)."""
        _, _, t = polyline_tangent(self.tasks[obs.snapshot.ids[row]].path, x)
        return self._room_ahead(obs, row, at=np.asarray(x, float), heading=math.atan2(t[1], t[0])) >= self.p.sa_free_ahead_m
