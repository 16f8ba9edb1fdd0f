"""One ego's road in its route frame (SPEC §5), for every road-going controller.

Per step :meth:`RoadView.scene` maps what the ego perceives into Frenet coordinates (s along the
reference path, d across it, positive left; :class:`~sumo_avoid.road.frenet.RouteFrame`): the ego,
the other vehicles' footprints (centre, heading relative to the path, length, width, velocity
(s_dot, d_dot)) and the bounds of the lanes of its own direction
(:class:`~sumo_avoid.road.route_lanes.RouteLanes`). Vehicles wholly outside those lanes (oncoming traffic
beyond the centre line, cars on a road nearby) are left out: the ego keeps to its lanes, and one
that enters them is an obstacle from then on. In that frame a bend or a turn is straight, so a
field computed there keeps the car in its lane through it; :meth:`RoadView.to_xy_velocity` maps
the command back. A footprint's shape is kept as a rectangle in (s, d) (its curvature over a few
metres is neglected). docs/road_frame.md has the formulas.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from sumo_avoid.road.drivable import NONE, drivable_line
from sumo_avoid.road.frenet import RouteFrame
from sumo_avoid.road.gaps import GAP_MIN_M, lane_blockers, lane_change_length_m
from sumo_avoid.core.geometry import wrap_angle
from sumo_avoid.road.route_lanes import RouteLanes
from sumo_avoid.road.polyline import arc_lengths
from sumo_avoid.road.regulation import legal_limits, limit_index
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.sensing.perception import obstacle_vehicles, on_carriageway, towards_path

#: Vehicles farther than this across the path are not part of the ego's road scene, m.
MAX_ABS_D_M = 20.0
#: A vehicle whose footprint stays this far outside the ego's lanes is no obstacle to it, m.
OUTSIDE_MARGIN_M = 0.2
#: On a drivable line the bounds of the lanes stay at least this far from a car on it, m.
LINE_CLEAR_M = 1.0
#: On a drivable line, the speed leaves this share of the largest yaw rate for corrections.
YAW_RESERVE = 0.75
#: A car waiting for a gap to change lanes stops this far before its lane starts to taper off, m.
LANE_END_CLEAR_M = 1.0
#: ... and drops back this much below the speed of a car that blocks it from ahead in the lane it needs, m/s;
DROP_BACK_MPS = 2.0
#: ... it goes once that lane has been free this long, s; a change is under way once the ego is this far
#: from its lane's centre towards the next, m.
LANE_FREE_S = 1.0
COMMIT_M = 0.5
#: ... past a car behind in the target lane slower than this (it waits for the ego), m/s
YIELDING_MPS = 0.5
#: Changes are held only where the lane the ego needs runs straighter than this radius where the
#: lane it is in tapers off, m. On a roundabout's ring holding the inner lane while braking for ring
#: cars swings the car over the kerb; there the path blends across and the field keeps it off the
#: ring's cars.
HOLD_RADIUS_M = 100.0
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
    o_grow: np.ndarray | None = None  # (O,) how much each one's length and width grew by its VRU margin, m (None: 0)
    one_sided_m: float = 0.0  # of the corridor's width at s, the junction widening that lies on one side only, m
    o_kerb: np.ndarray | None = None  # (O,) bool: a person on a walkway, behind the kerb (None: none)

    @property
    def q(self) -> np.ndarray:
        return np.array([self.s, self.d])

    @property
    def kerb_only(self) -> np.ndarray:
        """(O,) bool: people on a walkway who keep no VRU margin (standing, or walking along the kerb)."""
        if self.o_kerb is None or not len(self.o_kerb):
            return np.zeros(len(self.o_pos), bool)
        return self.o_kerb & ((self.o_grow if self.o_grow is not None else np.zeros(len(self.o_pos))) <= 0.0)

    def body_span(self) -> tuple[np.ndarray, np.ndarray]:
        """(O,) each: the d span of each road user's own body, without the VRU margin its footprint grew by. The
        grown box turned by h reaches (|sin h| + |cos h|) x the margin further across the road than the body, not
        the margin once: a cyclist standing at 45 degrees across the next internal lane, 0.8 m clear of the ego's
        strip, counted as in it and held the ego inside the junction for good while the cyclist waited for the
        ego (unseen Coimbatore, car102, 348 s)."""
        grow = self.o_grow if self.o_grow is not None else np.zeros(len(self.o_pos))
        c, s = np.abs(np.cos(self.o_heading)), np.abs(np.sin(self.o_heading))
        half = 0.5 * ((self.o_length - grow) * s + (self.o_width - grow) * c)
        return self.o_pos[:, 1] - half, self.o_pos[:, 1] + half


class RoadView:
    """The route frame and lanes of one ego, with its arc length tracked from step to step."""

    def __init__(self, task: EgoTask, turn_radius_m: float = 0.0, yaw_rate_radps: float = np.inf):
        self.frame = RouteFrame.from_polyline(task.path)
        self.lanes = RouteLanes(task.lanes) if task.lanes else None
        self.walkways = task.walkways  # people there are off the carriageway: no margin beyond their size
        self.passing: tuple[float, float] | None = None  # (s_from, s_to): the oncoming lane is the ego's too (a pass)
        # d is measured from the drivable line (core.drivable), not the lane centre, where a turn
        # is tighter than the car's turning radius; elsewhere (and with no radius) they coincide
        self.line = (drivable_line(self.frame, self.lanes.corridor, 0.5 * task.width_m, turn_radius_m)
                     if self.lanes is not None else NONE)
        self.yaw_rate_radps = yaw_rate_radps
        self.turn_radius_m = turn_radius_m
        self._room = 0.5 * task.width_m + LINE_CLEAR_M
        self._line_frame = None  # the line's own frame and its arc length at the line's grid: its curvature, its direction
        if len(self.line.s):
            xy = self.frame.to_xy(self.line.s, self.line.d)
            # curvature smoothed over 1 m, not 5: the line's swing out before a tight turn is a few metres
            # long; counted only along the line's stretches (elsewhere the lane frame's 5 m smoothing
            # holds: over 1 m a polyline kink reads as a tight bend)
            arc = arc_lengths(xy)
            frame = RouteFrame.from_polyline(xy, smooth_m=1.0)
            g = frame.grid_s0_m + frame.grid_step_m * np.arange(len(frame.kappa_grid))
            s_g = np.interp(g, arc, self.line.s)
            on = np.zeros(len(g), bool)
            for ds in (-2.0, 0.0, 2.0):
                on |= np.abs(self.line.offset(s_g + ds)) > 1e-9
            self._line_frame = (replace(frame, kappa_grid=np.where(on, frame.kappa_grid, 0.0)), self.line.s, arc)
        gs, gd = self.frame.to_frenet(np.asarray(task.goal, float)[None, :])
        self.goal = np.array([gs[0], gd[0] - self.line.offset(gs)[0]])
        self._s: float | None = None
        self._held_free_s: float | None = None  # a held lane change: how long its lane has been free, s
        self._limits = legal_limits(task.speed_limits)  # the normal lanes' (not netconvert's turning speeds)

    @property
    def length_m(self) -> float:
        return self.frame.length_m

    def inside(self, s: float, d: float, half_m: float) -> float:
        """d moved inside the corridor at s by ``half_m`` (the middle where it is narrower than 2 half_m). An
        offset chosen where the lanes were wide and carried forward lay beyond a tapering lane's bound, whose
        push then swung the car across (berlin_bike_tram seed 3: d = 3.2 m against a bound falling to 2.9 m);
        the path's own line (d = 0) lies inside its lanes by construction."""
        lo, hi = (float(b[0]) for b in self.corridor([s]))
        return min(max(d, lo + half_m), hi - half_m) if hi - lo >= 2.0 * half_m else 0.5 * (lo + hi)

    def legal_speed(self, s: float) -> float:
        """The legal speed limit at arc length s (its normal lane's; the one before a junction runs on through
        it), m/s; inf without limits. What a car at that limit does is cruise, not crawl."""
        if self._limits is None:
            return np.inf
        return float(self._limits[limit_index(self._limits, s), 1])

    def locate(self, xy) -> tuple[float, float]:
        """(s, d) of the ego's centre, projected near where it was last step (a path that passes
        a place twice is not confused)."""
        hint = None if self._s is None else np.array([self._s])
        s, d = self.frame.to_frenet(np.asarray(xy, float)[None, :], hint, TRACK_WINDOW_M)
        self._s = float(s[0])
        return float(s[0]), float(d[0] - self.line.offset(s)[0])

    def corridor(self, s) -> tuple[np.ndarray, np.ndarray]:
        if self.lanes is None:
            s = np.atleast_1d(np.asarray(s, float))
            return np.full(len(s), -np.inf), np.full(len(s), np.inf)
        lo, hi = self.lane_bounds(s)
        off = self.line.offset(s)
        lo, hi = lo - off, hi - off
        # where the line swings close to a bound (by plan, to make a tight turn), the bound leaves the
        # car on the line room to spare: else its push holds the car off the line, inwards at a turn's
        # wide entry, and the car comes out against the oncoming lane at the exit
        wide = np.abs(off) > 1e-9
        return np.where(wide, np.minimum(lo, -self._room), lo), np.where(wide, np.maximum(hi, self._room), hi)

    def one_sided_widening(self, s: float) -> float:
        """How much of the corridor's width at s is junction widening on one side only, m: a kerb stops
        it on the other, where the car on its lane keeps only its lane's room."""
        if self.lanes is None:
            return 0.0
        m_lo, m_hi = self.lanes.widening([s])
        return float(abs(m_lo[0] - m_hi[0]))

    def lane_bounds(self, s) -> tuple[np.ndarray, np.ndarray]:
        """The bounds of the ego's lanes at arc lengths s (lane frame), with the oncoming lane while a
        pass borrows it (:attr:`passing`)."""
        s = np.atleast_1d(np.asarray(s, float))
        lo, hi = self.lanes.corridor(s)
        if self.passing is not None:
            a, b = self.passing
            hi = hi + np.where((s >= a) & (s <= b), self.lanes.opposite(s), 0.0)
        return lo, hi

    def lane_centres(self, s: float) -> np.ndarray | None:
        """d of every lane centre of the route's edge at arc length s (by lane index), or None."""
        if self.lanes is None:
            return None
        return self.lanes.centres(s)[1] - self.line.offset(s)[0]

    def lane_change(self, sc: FrenetScene, ahead_m: float, decel_mps2: float, step_s: float) -> tuple[float, float]:
        """Where the path changes lanes (an edge entered on a lane that does not lead on along the
        route), the lateral offset to follow (at the carrot, ``ahead_m`` ahead) and a speed limit,
        m/s, called once per step (``step_s``). (0, inf): follow the path into the next lane towards
        the route's, which is free beside the ego (:func:`~sumo_avoid.road.gaps.lane_blockers`: the
        secure gap to whatever it senses behind and ahead in that lane, and ahead the room the move
        takes at the car's turning radius). Otherwise the ego keeps to
        the centre of the lane it is in, drops back behind a car in the target lane that blocks it
        from ahead or alongside (``DROP_BACK_MPS`` below its speed: riding beside it, the gap never
        opens), and, at ``decel_mps2``, stops before its lane tapers off
        (:meth:`~sumo_avoid.road.route_lanes.RouteLanes.lanes_end_s`) to wait there for the gap. A held
        change goes once the lane has been free for ``LANE_FREE_S`` (so that the hold does not flip
        on and off as cars come and go, e.g. on a two-lane roundabout's ring); one under way (the
        ego ``COMMIT_M``
        towards the lane) is carried through unless a car is alongside in it. In a bend tighter than
        ``HOLD_RADIUS_M`` the path's blend is followed as it is."""
        if self.lanes is None:
            return 0.0, np.inf
        piece, centres = self.lanes.centres(sc.s)
        if len(centres) < 2 or piece.edge.startswith(":"):
            self._held_free_s = None
            return 0.0, np.inf
        centres = centres - self.line.offset(sc.s)[0]
        own = int(np.argmin(np.abs(centres - sc.d)))
        if own == piece.lane:
            self._held_free_s = None
            return 0.0, np.inf
        end = self.lanes.lanes_end_s(sc.s)
        if np.abs(self.frame.curvature_at(np.linspace(end - 5.0, end, 6))).max() > 1.0 / HOLD_RADIUS_M:
            self._held_free_s = None  # in a bend (a roundabout's ring): the path's own blend
            return 0.0, np.inf
        step = 1 if piece.lane > own else -1
        nxt = own + step
        band = (centres[nxt] - 0.5 * piece.widths_m[nxt], centres[nxt] + 0.5 * piece.widths_m[nxt])
        o_vs = sc.o_vel[:, 0]
        move = lane_change_length_m(centres[nxt] - sc.d, self.turn_radius_m)
        block = lane_blockers(sc.s, float(sc.vel[0]), sc.length, sc.o_pos, sc.o_length, sc.o_width, o_vs, band,
                              move_m=move)
        ds = sc.o_pos[:, 0] - sc.s
        alongside = block & (np.abs(ds) < 0.5 * (sc.length + sc.o_length) + GAP_MIN_M)
        # a car standing wholly behind the ego in that lane waits for it (it stopped for the ego's corner
        # in its lane): it does not hold a change under way, even one held before (berlin_bike_tram: the
        # ego half across, the car behind stopped 2.5 m back, each waited for the other to the end)
        waits = block & (o_vs < YIELDING_MPS) & (ds + 0.5 * (sc.length + sc.o_length) < 0.0)
        held = self._held_free_s is not None
        if block.any():
            all_wait = bool(waits[block].all())
            if all_wait and abs(float(sc.vel[0])) < YIELDING_MPS:
                # the ego stands, and all that is in the way stands wholly behind it in that lane: SUMO's drivers stop
                # there to let a car that must change lanes in (its lane-change model asks them to), so waiting for
                # them waits for ever (unseen Bengaluru car22: 121 s and on, the queue behind in both lanes)
                self._held_free_s = None
                return 0.0, np.inf
            toward = 1.0 if centres[nxt] > centres[own] else -1.0  # across the road (lane indices grow to the left
            # with right-hand traffic, to the right with left-hand: Chiang Mai car56 stood half across, the change
            # under way counted as none, clipped by a car coming up the next lane)
            if (toward * (sc.d - centres[own]) > COMMIT_M and not (alongside & ~waits).any()
                    and (not held or all_wait)):
                return 0.0, np.inf  # under way: carry it through
            self._held_free_s = 0.0
        elif not held:
            return 0.0, np.inf
        else:
            self._held_free_s += step_s
            if self._held_free_s >= LANE_FREE_S - 1e-9:
                self._held_free_s = None
                return 0.0, np.inf
        s_c = min(sc.s + ahead_m, max(end, sc.s))  # the carrot's s, on this edge
        hold = float(self.lanes.centres(s_c)[1][own] - self.line.offset(s_c)[0])
        v = float(np.sqrt(2.0 * decel_mps2 * max(end - LANE_END_CLEAR_M - (sc.s + 0.5 * sc.length), 0.0)))
        ahead = block & (ds >= 0.0)  # drop back to open the gap behind it
        if ahead.any():
            v = min(v, max(float(o_vs[ahead].min()) - DROP_BACK_MPS, 0.0))
        return hold, v

    def _line_axes(self, s):
        """(on (N,) bool, tangent (N, 2), normal (N, 2)): where s lies on a drivable line's stretch, the line's own
        directions there (its xy polyline's frame); (on, None, None) where s lies on none of them."""
        s = np.atleast_1d(np.asarray(s, float))
        if self._line_frame is None:
            return np.zeros(len(s), bool), None, None
        on = (np.abs(self.line.offset(s)) > 1e-9) | (self.line.slope(s) != 0.0)
        if not on.any():
            return on, None, None
        frame, grid, arc = self._line_frame
        n = frame.normal_at(np.interp(s, grid, arc))
        return on, np.stack([n[:, 1], -n[:, 0]], axis=-1), n  # (the tangent as RouteFrame.tangent_at turns it)

    def _from_line(self, s, d, rel_heading, vel, heading, vel_xy):
        """Lane-centre frame -> the drivable line's: d, relative heading and velocity (s_dot, d_dot)
        measured from the line: its offset at s, and on its stretches its own direction (``heading``, rad,
        and ``vel_xy`` (N, 2), m/s, in the plane). The lane frame's tangent plus the offset's slope is that
        direction only where the lane polyline turns smoothly; at a vertex that turns at once (unseen Chiang
        Mai, a 90-degree vertex in a 1.6 m lane) the slope turns the other way and the heading read 1 rad off."""
        slope = self.line.slope(s)
        vel = np.array(vel, float).reshape(-1, 2)
        vel[:, 1] -= vel[:, 0] * slope
        rel = wrap_angle(rel_heading - np.arctan(slope))
        on, t, n = self._line_axes(s)
        if on.any():
            v_xy = np.asarray(vel_xy, float).reshape(-1, 2)
            rel = np.where(on, wrap_angle(np.asarray(heading, float) - np.arctan2(t[:, 1], t[:, 0])), rel)
            vel = np.where(on[:, None], np.column_stack([np.einsum("ij,ij->i", v_xy, t),
                                                         np.einsum("ij,ij->i", v_xy, n)]), vel)
        return d - self.line.offset(s), rel, vel

    def scene(self, obs: Observation, row: int, sense_radius_m: float, vru_margin_m: float = 0.0) -> FrenetScene:
        snap = obs.snapshot
        q = snap.pos[row]
        s, d = self.locate(q)
        d_raw = d + float(self.line.offset(s)[0])
        h_path = float(self.frame.heading_at(s)[0])
        v_s, v_d = self.frame.velocity_to_frenet(s, d_raw, snap.vel[row][None, :])
        _, h_rel, vel = self._from_line(np.array([s]), d_raw, np.array([wrap_angle(snap.heading[row] - h_path)]),
                                        np.array([[v_s[0], v_d[0]]]), snap.heading[row:row + 1], snap.vel[row:row + 1])
        o_pos, o_hd, o_len, o_wid, o_vel, vru, kerb = obstacle_vehicles(obs, row, q, sense_radius_m, self.walkways)
        if len(o_pos):
            os_, od = self.frame.to_frenet(o_pos, np.full(len(o_pos), s), sense_radius_m)
            keep = np.isfinite(os_) & (np.abs(od) < MAX_ABS_D_M) & (np.abs(os_ - s) < sense_radius_m)
            os_, od = os_[keep], od[keep]
            o_hd, o_len, o_wid, o_vel, vru, kerb = o_hd[keep], o_len[keep], o_wid[keep], o_vel[keep], vru[keep], kerb[keep]
            o_rel = wrap_angle(o_hd - self.frame.heading_at(os_))
            # a vehicle wholly outside the ego's lanes (oncoming traffic beyond the centre line,
            # a car on a road nearby) is behind a bound the ego keeps to: not an obstacle to it; on a
            # drivable line's stretch the bound is the line's room (so a car standing at the end of the
            # oncoming lane beside a wide exit is not left out)
            half = 0.5 * (np.abs(np.sin(o_rel)) * o_len + np.abs(np.cos(o_rel)) * o_wid)
            lo, hi = self.lane_bounds(os_) if self.lanes is not None else self.corridor(os_)
            off = self.line.offset(os_)  # where the drivable line swings out, so does the room the car may use
            line_lo, line_hi = self.corridor(os_)
            lo, hi = np.minimum(lo, line_lo + off), np.maximum(hi, line_hi + off)
            keep = (od + half > lo - OUTSIDE_MARGIN_M) & (od - half < hi + OUTSIDE_MARGIN_M)
            lo_k, hi_k = lo[keep], hi[keep]
            os_, od, o_rel, o_len, o_wid, o_vel = os_[keep], od[keep], o_rel[keep], o_len[keep], o_wid[keep], o_vel[keep]
            kerb = kerb[keep]
            # a person or cyclist in or at the ego's lanes counts as grown by vru_margin_m all round (one
            # on the sidewalk beside them is behind the bound, as above: the ego passes it, not crawls), a
            # person on a walkway by its share of it (perception._weight) while it walks towards the ego's
            # path; one walking along the kerb is passed at its size (signal_crossing_right, radar, seed 1:
            # pushed 0.65 m over by people walking on the sidewalk, the ego met a car in the next lane); one on a
            # walkway with its centre well inside the ego's lanes is on the carriageway (unseen 2242: a person crossing
            # the ego's left turn on a walking area over its internal lane, walking away from the side the ego had
            # drifted to, was passed at its size; the ego, pushed back from the lane's edge, hit it at 2.4 m/s)
            vs, vd = self.frame.velocity_to_frenet(os_, od, o_vel)
            share, kerb = on_carriageway(np.asarray(vru, float)[keep], kerb, od, lo_k, hi_k)
            grow = 2.0 * vru_margin_m * towards_path(share, vd * np.sign(d_raw - od))
            o_len, o_wid = o_len + grow, o_wid + grow
            od, o_rel, o_vel = self._from_line(os_, od, o_rel, np.column_stack([vs, vd]),
                                               o_rel + self.frame.heading_at(os_), o_vel)
            o_pos = np.column_stack([os_, od])
        else:
            o_rel = np.zeros(0)
        return FrenetScene(s, d, float(h_rel[0]), vel[0],
                           float(snap.length[row]), float(snap.width[row]),
                           o_pos.reshape(-1, 2), o_rel, o_len, o_wid, o_vel.reshape(-1, 2), self.corridor,
                           grow if len(o_pos) else np.zeros(0), self.one_sided_widening(s),
                           kerb if len(o_pos) else np.zeros(0, bool))

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
        on, t, n = self._line_axes(s_ff)
        if on[0]:  # on a drivable line's stretch: along the line's own direction and across it (_from_line)
            xy = v[0] * t[0] + v[1] * n[0]
        else:
            d_raw = d + float(self.line.offset(s_ff)[0])  # back from the drivable line to the lane centre's frame
            xy = self.frame.velocity_to_xy(s_ff, d_raw, v[0], v[1] + v[0] * float(self.line.slope(s_ff)[0]))[0]
        norm = float(np.hypot(*xy))
        return xy / norm * speed if norm > 1e-12 else np.zeros(2)

    def curve_speed(self, s: float, a_lat_mps2: float, decel_mps2: float) -> float:
        """Speed for the road ahead from its curvature (RouteFrame.curve_speed_limit, full envelope):
        of the lane centres and, where the car drives a drivable line, of that line too (its wide
        entry bends the other way before the turn: a car still fast there cannot follow it)."""
        v = float(self.frame.curve_speed_limit(s, np.inf, a_lat_mps2, decel_mps2)[0])
        if self._line_frame is not None:
            frame, grid, arc = self._line_frame
            sl = np.interp(s, grid, arc)
            v = min(v, float(frame.curve_speed_limit(sl, np.inf, a_lat_mps2, decel_mps2)[0]))
            if np.isfinite(self.yaw_rate_radps):  # and slow enough to turn with YAW_RESERVE of the yaw rate to spare
                k = float(frame.max_abs_curvature_ahead(sl, 2.0)[0])
                if k > 0.0:
                    v = min(v, YAW_RESERVE * self.yaw_rate_radps / k)
        return v
