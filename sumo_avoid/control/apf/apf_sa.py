"""``apf_sa``: the potential field of :mod:`.apf` plus simulated-annealing escape (SPEC §2, seed 001 §2.2, Fig. 2).

Trap detector (documented choice): an ego is *trapped* when, over the last ``trap_window_s``, it advanced
along its route less than ``trap_progress_frac * cruise * window`` **and** right now either the force has
almost vanished (``|F| < trap_force_frac * F_att_max``, the field's local minimum) or the speed governor
holds it below cruise (an obstacle it cannot pass sits in its corridor): a car slowed in a bend is not
trapped, one behind a stopped obstacle is -- but behind a queue at a stop line (:mod:`.queue`) it waits.

Everything runs in the ego's route frame (s, d), like :mod:`.apf`. Simulated annealing (seed Fig. 2) on the field
frozen at that instant: from x = the ego's centre (s, d), draw x1 = x + step (cos a, sin a) with a uniform; positions whose footprint leaves the lanes of the
ego's direction are refused; Delta = U(x1) - U(x); accept when Delta <= 0 or exp(-Delta/T) > u (u uniform);
cool T <- T * ``sa_cooling`` after each draw; stop when the walk is at least ``sa_escape_m`` from
the trap with a potential below the trap's (it has left the basin), or after ``sa_max_iter``
draws (then no escape this time, and the next search waits ``trap_window_s`` x 2^(failures in a
row), at most ``sa_backoff_max_s``; a search costs up to ``sa_max_iter`` field evaluations). A car cannot jump to x1, so the walk's end point becomes an
*escape target*: the ego follows the reference path shifted sideways by the end point's d
(e.g. the free lane) until it has held that offset for ``escape_hold_s`` or ``escape_timeout_s`` has passed; then plain APF resumes.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from sumo_avoid.control.apf.anneal import anneal
from sumo_avoid.control.apf.apf import ApfDriver, ApfParams
from sumo_avoid.control.apf.oncoming_pass import ABORT_D_M, PASS_CARROT_MIN_M, OncomingPass, PassParams
from sumo_avoid.control.apf.queue import STAND_MPS, lane_runs_past, waits_in_queue
from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.control.road_view import FrenetScene, RoadView
from sumo_avoid.core.config import FieldError, field_doc
from sumo_avoid.core.geometry import footprint_corners
from sumo_avoid.core.types import EgoTask, Keys, Observation
from sumo_avoid.road.gaps import lane_change_length_m
from sumo_avoid.sensing.radar import RadarParams


@dataclass(frozen=True)
class ApfSaParams:
    """``[controllers.apf_sa]``: the field's parameters (:class:`~.apf.ApfParams`, the same keys as
    ``[controllers.apf]``, in this table) and those of the trap detector and the escape search."""

    apf: ApfParams = field_doc(default_factory=ApfParams, inline=True, doc="the potential field's keys")
    trap_window_s: float = field_doc(2.0, doc="progress is judged over this window, s")
    trap_progress_frac: float = field_doc(0.7, doc="trapped below this fraction of cruise progress")
    trap_force_frac: float = field_doc(0.05, doc="|F| below this fraction of F_att_max = a minimum")
    sa_step_m: float = field_doc(1.0, doc="SA step length, m")
    sa_t0: float = field_doc(10.0, doc="SA initial temperature (potential units)")
    sa_cooling: float = field_doc(0.995, doc="SA cooling factor per draw (geometric schedule)")
    sa_max_iter: int = field_doc(1000, doc="SA draws per escape search (seed: 1000)")
    sa_escape_m: float = field_doc(3.0, doc="the walk has left the minimum this far from the trap, m")
    sa_free_ahead_m: float = field_doc(20.0, doc="the walk has left the basin where this much is free ahead along the route, m")
    sa_backoff_max_s: float = field_doc(16.0, doc="after a search finds no escape the next waits trap_window_s, "
                                                  "doubled per failure in a row up to this, s (behind a slow truck "
                                                  "with oncoming traffic, 24 fruitless searches took 3/4 of a run's "
                                                  "CPU time)")
    escape_hold_s: float = field_doc(3.0, doc="keep the escape offset this long once reached, s")
    escape_timeout_s: float = field_doc(10.0, doc="give up an escape after this long without getting "
                                                  "escape_progress_m closer to its offset or backing up, s")
    escape_progress_m: float = field_doc(0.5, doc="lateral progress towards the offset that restarts the timeout, m")
    escape_max_s: float = field_doc(40.0, doc="give up an escape after this long in any case, s")
    queue_reach_m: float = field_doc(15.0, doc="a queue (control/apf/queue.py) starts this close to a stop line, m ...")
    queue_patience_s: float = field_doc(30.0, doc="... in one the ego starts no escape before it has stood this long, s")
    escape_room_m: float = field_doc(12.0, doc="when blocked, back up until this much room (at least the "
                                               "carrot distance, lookahead_min_m) is free ahead along the route, m")
    escape_reverse_speed_mps: float = field_doc(1.5, doc="speed while backing up, m/s")
    reverse_clear_m: float = field_doc(3.0, doc="backing up only while nothing is behind in the ego's strip "
                                                "nearer than this ...")
    reverse_clear_s: float = field_doc(3.0, doc="... plus this times the closing speed (the ego backing, the "
                                                "other driving on), s")
    reverse_side_clear_m: float = field_doc(0.5, doc="... and no one moving (or a person or cyclist) alongside the ego "
                                                     "nearer than this to its sides: backing up turns the car, and its "
                                                     "nose swings sideways, m")
    escape_margin_m: float = field_doc(0.5, doc="the escape target keeps the car this far from road edges, m")
    passing: PassParams = field_doc(default_factory=PassParams, inline=True,
                                    doc="the oncoming-lane pass's keys (control/apf/oncoming_pass.py)")

    def __post_init__(self):
        if not 0.0 < self.sa_cooling < 1.0:
            raise FieldError("sa_cooling", "a cooling factor in (0, 1) (T shrinks each draw)", self.sa_cooling)


@dataclass
class _EgoState:
    history: deque  # (time_s, arc length s_m)
    escape_offset: float | None = None
    escape_start_s: float = 0.0
    escape_clock_s: float = 0.0  # when the escape last got closer to its offset (or was backing up)
    escape_err_m: float = math.inf  # the smallest |d - offset| so far
    held_since_s: float | None = None
    cooldown_until_s: float = -math.inf
    reversing: bool = False
    failures: int = 0  # searches in a row that found no escape (the wait before the next doubles)
    pass_rear_s: float = math.nan  # while passing: the blocker's rear (s); the pass is called off before it
    pass_checked_s: float = -math.inf  # when the oncoming lane was last looked at for a pass
    pass_ready: bool = False  # behind a vehicle it may pass, waiting for the oncoming lane: room made, held
    stood_since_s: float | None = None  # standing (slower than queue.STAND_MPS) since


class ApfSaController(BaseController):
    """The potential field plus a simulated-annealing escape from its local minima, in each ego's route frame."""

    stats_keys = Keys(("sa_escapes", "sa_failed_searches", "sa_oncoming_passes"))  # what stats() writes

    def __init__(self, params: ApfSaParams, ctx):
        super().__init__(params, ctx)
        self.driver = ApfDriver(params.apf, ctx)  # the field it drives and searches
        self.rng = ctx.rng()
        self.state: dict[str, _EgoState] = {}
        self.escapes = 0
        self.failed_searches = 0
        self.passer = OncomingPass(params.passing, params.escape_reverse_speed_mps, params.apf.max_lat_speed_mps)
        radar = getattr(ctx, "params", {}).get("sensors.radar")  # how far the front radar sees (the pass's look ahead)
        self.radar_sight_m = (radar if radar is not None else RadarParams()).max_range_m
        self.passes = 0

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        self.driver.add_ego(task)
        self.state[task.vid] = _EgoState(deque())

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        self.driver.remove_ego(vid)
        self.state.pop(vid, None)
        self.passer.forget(vid)

    def stats(self) -> dict:
        return {"sa_escapes": self.escapes, "sa_failed_searches": self.failed_searches,
                "sa_oncoming_passes": self.passes}

    def act(self, obs: Observation) -> np.ndarray:
        p, a, drv = self.p, self.p.apf, self.driver
        out = np.zeros((len(obs.ego_ids), 2))
        f_max = a.k_att * a.d_att_m
        t = obs.snapshot.time_s
        # backing up needs a view behind: ground truth, or a rear radar (a front radar does not see the cars behind)
        sees_behind = obs.detections is None or any(d.mount == "rear" for d in obs.detections)
        for k, (vid, row) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            task, st, view = self.tasks[vid], self.state[vid], drv.views[vid]
            sc = drv.scene(obs, row, vid)
            speed = float(np.hypot(*sc.vel))
            if view.passing is not None:
                self._keep_passing(view, sc, st, obs, row, task)
            if st.escape_offset is not None:
                self._update_escape(st, sc.d, t)
            st.history.append((t, sc.s))
            st.stood_since_s = (st.stood_since_s if st.stood_since_s is not None else t) if speed < STAND_MPS else None
            while st.history and st.history[0][0] < t - p.trap_window_s - 1e-9:
                st.history.popleft()
            offset, v_lane = view.lane_change(sc, drv.lookahead(speed), a.gov_decel_mps2, drv.step_s)  # the path's lane changes wait for a gap
            if st.escape_offset is not None:
                offset, v_lane = st.escape_offset, np.inf
            target = drv.carrot(view, sc, offset, self._pass_reach(view, sc, st))
            fld = drv.field(sc, sc.q[None, :], target)
            force = float(np.hypot(*fld.F[0]))
            v_road = min(drv.road_speed(view, sc), v_lane)  # waiting for a gap is not being trapped
            # a car slowed for a bend is not trapped, nor one at the legal limit (on a 30 km/h street every car ahead
            # made a trap of it: berlin_bike_tram seed 3 escaped into a lane ending 11 m on, beside a car pulling out)
            v_cruise = min(task.cruise_speed_mps, view.legal_speed(sc.s))
            v_ref = min(v_cruise, v_road)

            window_full = st.history[-1][0] - st.history[0][0] >= p.trap_window_s - 1e-9
            progress = st.history[-1][1] - st.history[0][1]
            slow = progress < p.trap_progress_frac * v_ref * p.trap_window_s
            stuck_now = (force < p.trap_force_frac * f_max or fld.v_safe < 0.9 * v_ref
                         or (speed < 0.5 and math.isfinite(fld.v_safe)))
            if window_full and progress >= p.trap_progress_frac * v_cruise * p.trap_window_s:
                st.failures = 0  # at cruise progress again (not merely slowed for a bend): a new trap next
            if (view.passing is None and st.escape_offset is None and window_full and slow and stuck_now
                    and t >= st.pass_checked_s + 1.0):
                st.pass_checked_s = t
                self._try_pass(vid, view, sc, st, obs, row, task)
            if (st.escape_offset is None and window_full and slow and stuck_now and
                    (t >= st.cooldown_until_s or (view.passing is not None and st.pass_checked_s == t)) and
                    not waits_in_queue(sc, task, view.length_m, 0.0 if st.stood_since_s is None else t - st.stood_since_s,
                                       p.queue_reach_m, p.queue_patience_s)):
                end = anneal(self.driver, self.rng, self.p, view, sc, target, self._room_ahead)
                offset = None if end is None else self._inside_offset(view, sc, end)
                if end is None:
                    self.failed_searches += 1
                    st.cooldown_until_s = t + min(p.trap_window_s * 2.0**st.failures, p.sa_backoff_max_s)
                    st.failures += 1
                elif not ((view.passing is not None or lane_runs_past(view, sc, offset)) and  # (a pass: its stretch)
                          self._room_to_escape(sc, offset, sees_behind)):  # no lane past it, or no room yet: wait
                    st.cooldown_until_s = t + p.trap_window_s
                else:
                    self.escapes += 1
                    st.failures = 0
                    st.escape_offset = offset
                    st.escape_start_s = st.escape_clock_s = t
                    st.held_since_s, st.escape_err_m = None, math.inf
                    target = drv.carrot(view, sc, st.escape_offset)
                    fld = drv.field(sc, sc.q[None, :], target)
            v = drv.velocity(fld, task.cruise_speed_mps, v_road, float(np.hypot(*sc.vel)),
                             may_reverse=sees_behind and self._clear_behind(sc))
            if st.escape_offset is not None:
                v = self._make_room(st, sc, v, fld.v_safe, sees_behind, view.passing is not None)
            elif st.pass_ready:
                v = self._wait_to_pass(st, sc, sees_behind)
            out[k] = view.to_xy_velocity(sc.s, sc.d, v, drv.step_s)
        return out

    def _oncoming(self, view: RoadView, obs: Observation, row: int, sc: FrenetScene):
        """A function (s_from, s_far) -> [(s, s_dot)] of the vehicles sensed in the oncoming lane there."""
        def sensed(s_from: float, s_far: float):
            keep, view.passing = view.passing, (s_from, s_far)
            try:
                wide = view.scene(obs, row, s_far - sc.s + 10.0)
            finally:
                view.passing = keep
            if not len(wide.o_pos):
                return []
            _, own_hi = view.corridor(wide.o_pos[:, 0])  # own lanes only (passing restored)
            half = 0.5 * np.minimum(wide.o_length, wide.o_width)
            mask = (wide.o_pos[:, 1] - half > own_hi - 0.3) & (wide.o_pos[:, 0] > s_from)
            return list(zip(wide.o_pos[mask, 0].tolist(), wide.o_vel[mask, 0].tolist()))
        return sensed

    def _try_pass(self, vid, view, sc, st, obs, row, task) -> None:
        sight = self.radar_sight_m if obs.detections is not None else math.inf
        t = obs.snapshot.time_s
        stretch = self.passer.start(vid, view, sc, t, task, task.cruise_speed_mps, sight,
                                    self._oncoming(view, obs, row, sc))
        if stretch is not None:
            s_from, s_to, st.pass_rear_s = stretch
            view.passing = (s_from, s_to)
            self.passes += 1
            st.pass_ready = False
        elif np.hypot(*sc.vel) <= 0.3:  # decided standing (backing up to make room it keeps its decision)
            # the oncoming lane is not free yet: make the room the pass starts from now (as _make_room
            # would once it is), so the pass then needs only its own time (sees behind: may back up)
            sees_behind = obs.detections is None or any(d.mount == "rear" for d in obs.detections)
            st.pass_ready = sees_behind and self.passer.candidate(vid, view, sc, t, task) is not None

    def _room_to_escape(self, sc: FrenetScene, offset: float, sees_behind: bool) -> bool:
        """May an escape towards ``offset`` (d) start? Where the room ahead holds the move across
        (:func:`~sumo_avoid.road.gaps.lane_change_length_m` + ``gov_standstill_m``), or where it can back
        up for it (it sees behind, nothing is there: ``_make_room``). Else it would stop across two lanes,
        and with a front radar alone not back out (Bologna: 22 s askew, passing cars clipping its rear)."""
        need = lane_change_length_m(offset - sc.d, self.driver.steering[0]) + self.p.apf.gov_standstill_m
        return self._room_ahead(sc, heading=0.0) >= need or (sees_behind and self._clear_behind(sc))

    def _pass_reach(self, view: RoadView, sc: FrenetScene, st: _EgoState) -> float:
        """How far ahead the carrot may lie: while a pass moves the ego out behind the blocker, half the
        gap to the blocker's rear (at least ``PASS_CARROT_MIN_M``), so that it is out before it gets
        there (the carrot's usual 15 m turn it out too slowly from the room it starts in)."""
        if view.passing is None or not math.isfinite(st.pass_rear_s):
            return math.inf
        gap = st.pass_rear_s - (sc.s + 0.5 * sc.length)
        return max(0.5 * gap, PASS_CARROT_MIN_M) if gap > 0.0 else math.inf

    def _wait_to_pass(self, st: _EgoState, sc: FrenetScene, sees_behind: bool) -> np.ndarray:
        """Behind a vehicle it may pass, the oncoming lane not yet free: back up straight along the road
        until ``escape_room_m`` (at least the carrot distance) is free ahead, then stand; on as soon as no
        vehicle stands ahead any more."""
        if self.passer.blocker(sc) is None:
            st.pass_ready = False
            st.history.clear()
            return np.zeros(2)
        room = self._room_ahead(sc, heading=0.0)
        if room >= self.p.passing.pass_room_m or not (sees_behind and self._clear_behind(sc)):
            return np.zeros(2)
        return self._back_up(sc)

    def _keep_passing(self, view, sc, st, obs, row, task) -> None:
        """End the pass once the ego's rear is past its stretch; call it off while the ego is still in its
        lane, short of the blocker, and the oncoming lane stops being free for it."""
        s_to = view.passing[1]
        done = sc.s - 0.5 * sc.length > s_to
        if not done and sc.s + 0.5 * sc.length < st.pass_rear_s and abs(sc.d) < ABORT_D_M:
            s_end, t_pass = self.passer.need(view, sc, s_to, task.cruise_speed_mps)
            reach = s_end - sc.s + self.p.passing.pass_oncoming_mps * (t_pass + self.p.passing.pass_margin_s)
            done = not self.passer.clear(self._oncoming(view, obs, row, sc)(view.passing[0], sc.s + reach), s_end, t_pass)
        if done:
            view.passing = None
            st.escape_offset, st.held_since_s, st.reversing = None, None, False

    def _inside_offset(self, view: RoadView, sc: FrenetScene, end) -> float:
        """The lateral offset the ego follows after an escape search ended at ``end`` = (s, d).

        The centre of the nearest lane that is as free ahead of the end point as the search
        demanded (``sa_free_ahead_m``; SPEC §5: the ego keeps to the centre of the lane it chose:
        from an end point between lanes the ego passes a car too closely on overtaking; the nearest
        centre regardless of what stands in that lane can send it back behind the obstacle), else
        the end point's own offset, shrunk until the shifted carrot keeps the
        car inside its lanes with ``escape_margin_m`` to spare on each side (a target on the kerb
        is no target)."""
        offset = float(end[1])
        need = 0.5 * sc.width + self.p.escape_margin_m
        s_c = min(sc.s + self.driver.lookahead(float(np.hypot(*sc.vel))), view.length_m)  # the carrot's s
        lo, hi = (float(v[0]) for v in view.corridor([s_c]))
        centres = view.lane_centres(s_c)
        if centres is not None:
            for c in sorted((float(c) for c in centres), key=lambda c: abs(c - offset)):
                if (lo + need <= c <= hi - need and self._room_ahead(
                        sc, at=(float(end[0]), c), heading=0.0) >= self.p.sa_free_ahead_m):
                    return c
        for k in range(int(abs(offset) / 0.25) + 1):
            o = math.copysign(max(abs(offset) - 0.25 * k, 0.0), offset)
            if lo + need <= o <= hi - need:
                return o
        return 0.0

    def _make_room(self, st: _EgoState, sc: FrenetScene, v_des, v_safe: float, sees_behind: bool, passing: bool):
        """A car cannot step sideways: when the escape is blocked straight ahead (the governor allows
        no speed) it backs up until ``escape_room_m`` (at least the carrot's distance; a pass:
        ``pass_room_m``, its carrot is nearer) is free on the line towards the escape target, then
        drives the escape forward. Needs ``actuator.max_reverse_speed_mps > 0``."""
        if not st.reversing and v_safe < 0.5 and float(np.hypot(*sc.vel)) < 0.3:
            st.reversing = True
        if st.reversing:
            room = self._room_ahead(sc, heading=0.0)
            if room >= (self.p.passing.pass_room_m if passing else max(self.p.escape_room_m, self.driver.lookahead(0.0))):
                st.reversing = False
                return v_des
            if not (sees_behind and self._clear_behind(sc)):  # never back into traffic, nor blind
                return np.zeros(2)
            return self._back_up(sc)
        return v_des

    def _back_up(self, sc: FrenetScene) -> np.ndarray:
        """Reverse against the route direction, so the nose straightens while the lateral offset
        already won is kept (a three-point manoeuvre rather than undoing the turn)."""
        fwd = np.array([math.cos(sc.heading), math.sin(sc.heading)])
        return self.p.escape_reverse_speed_mps * (np.array([-1.0, 0.0]) if fwd[0] > 0.0 else -fwd)

    def _strip(self, sc: FrenetScene, pos, heading: float):
        """The other vehicles against a strip of half width W/2 + ``gov_margin_m`` through ``pos``
        (s, d) along ``heading``: their corners' positions along it (O, 4), m, and which of them
        reach into it across (O,)."""
        x, y = self._across(sc, pos, heading)
        half = 0.5 * sc.width + self.p.apf.gov_margin_m
        return x, (y.max(axis=1) >= -half) & (y.min(axis=1) <= half)

    @staticmethod
    def _across(sc: FrenetScene, pos, heading: float):
        """The other vehicles' corners along and across a line through ``pos`` (s, d) along ``heading``, (O, 4) each, m."""
        hd = np.array([math.cos(heading), math.sin(heading)])
        rel = footprint_corners(sc.o_pos, sc.o_heading, sc.o_length, sc.o_width) - pos
        return rel @ hd, rel @ np.array([-hd[1], hd[0]])

    def _room_ahead(self, sc: FrenetScene, at=None, heading=None) -> float:
        """Free length ahead of the ego's footprint (placed at ``at`` with ``heading``, in (s, d)), m."""
        if not len(sc.o_pos):
            return math.inf
        x, in_strip = self._strip(sc, sc.q if at is None else np.asarray(at, float),
                                  sc.heading if heading is None else heading)
        ahead = in_strip & (x.max(axis=1) > 0)
        if not ahead.any():
            return math.inf
        return float(max(x[ahead].min(), 0.0) - 0.5 * sc.length)

    def _clear_behind(self, sc: FrenetScene) -> bool:
        """May the ego back up? No vehicle in its road-aligned strip behind it nearer, bumper to
        bumper, than ``reverse_clear_m`` + ``reverse_clear_s`` x the speed at which the two close
        (the ego backing at ``escape_reverse_speed_mps``, the other driving on: SUMO's drivers do not
        expect a car to come back at them)."""
        if not len(sc.o_pos):
            return True
        x, y = self._across(sc, sc.q, 0.0)  # the road-aligned strip's frame
        half = 0.5 * sc.width + self.p.apf.gov_margin_m
        behind = (y.max(axis=1) >= -half) & (y.min(axis=1) <= half) & (x.min(axis=1) < 0.0)
        gap = -x.max(axis=1) - 0.5 * sc.length
        closing = np.maximum(sc.o_vel[:, 0], 0.0) + self.p.escape_reverse_speed_mps
        return not (behind & (gap < self.p.reverse_clear_m + self.p.reverse_clear_s * closing)).any() and \
            not self._alongside(sc, x, y).any()

    def _alongside(self, sc: FrenetScene, x, y) -> np.ndarray:
        """(O,) bool: road users beside the ego's footprint (taken as aligned with the road; ``x``, ``y`` their corners
        along and across it), within ``reverse_side_clear_m`` of its sides, that move or keep a VRU margin
        (berlin_eastbound, seed 3: the ego backed up and turned 15 degrees while a cyclist squeezed past it, and its
        nose swung into him)."""
        half_l, half_w = 0.5 * sc.length, 0.5 * sc.width + self.p.reverse_side_clear_m
        along = (x.max(axis=1) > -half_l) & (x.min(axis=1) < half_l)
        near = (y.max(axis=1) >= -half_w) & (y.min(axis=1) <= half_w)
        grow = sc.o_grow if sc.o_grow is not None else np.zeros(len(sc.o_pos))
        return along & near & ((np.hypot(*sc.o_vel.T) >= 0.3) | (grow > 0.0))

    def _update_escape(self, st: _EgoState, d: float, t: float) -> None:
        """An escape ends once its offset has been held ``escape_hold_s``, or after
        ``escape_timeout_s`` in which it neither got ``escape_progress_m`` closer to the offset
        nor backed up (a three-point manoeuvre gains its offset in steps, backing up in between),
        and in any case after ``escape_max_s``."""
        p = self.p
        err = abs(d - st.escape_offset)
        if err < 1.0:
            st.held_since_s = t if st.held_since_s is None else st.held_since_s
        if st.reversing or err <= st.escape_err_m - p.escape_progress_m:
            st.escape_clock_s = t
            st.escape_err_m = min(err, st.escape_err_m)
        if (t - st.escape_clock_s >= p.escape_timeout_s or t - st.escape_start_s >= p.escape_max_s
                or (st.held_since_s is not None and t - st.held_since_s >= p.escape_hold_s)):
            st.escape_offset, st.held_since_s, st.reversing = None, None, False
            st.history.clear()
            st.cooldown_until_s = t + p.trap_window_s
