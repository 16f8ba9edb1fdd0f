"""``apf``: artificial potential field on a road (SPEC §2, seed 001), in the ego's route frame (SPEC §5).

Everything is computed in Frenet coordinates (s along the route's reference path, d across it;
:mod:`sumo_avoid.control.road_view`): a bend, a junction turn or a ramp looks straight to the
field, and the command is mapped back to the plane. Per ego and step:

* **Attraction** (SPEC §2, seed eq. 13-14, capped beyond ``d_att_m``) towards a *carrot*: the
  point ``lookahead`` metres ahead of the ego along its route, (s + lookahead, d_lane) with d_lane
  the centre of the lane it keeps (0: the path's lane; an escape's offset), or the goal once it is
  closer than that. Its lateral part is the lane-keeping pull towards d_lane.
* **Repulsion** (SPEC §2, seed eq. 3-8) ``K (1/rho - 1/rho0) / rho^2`` from every other vehicle's
  footprint (rho = footprint-to-footprint distance, direction from the obstacle's nearest point
  to the ego's) and, with its own gain and influence distance, across the road from the bounds of
  the lanes of the ego's direction (rho = distance in d from the footprint's nearest corner to the
  bound at that corner's s, always pushing inwards) (:class:`~sumo_avoid.road.route_lanes.RouteLanes`: the road edge, a two-way road's
  centre line, inside a junction the internal lane of the route, where lanes end). For the bounds
  the footprint is taken as aligned with the road, so that their push depends on where the car
  is, not on its heading: measured from the real corners, a heading error moves a front corner
  towards one bound, its push turns the car towards the other, and on a narrow lane the car weaves
  from bound to bound.
* **Influence distance from speed and braking**: ``rho0 = rho0_min + max(cos(phi), 0) *
  (v_close^2 / (2 b) + t_h |v|)`` with ``phi`` the bearing of the obstacle from the heading and
  ``v_close`` the closing speed: an obstacle ahead is felt from the stopping distance, one beside
  only from ``rho0_min``. A vehicle whose footprint does not overlap the ego's across the road
  (d, with ``gov_margin_m``; oncoming traffic in its lane, a car in the next lane) is felt from
  ``rho0_beside_m`` plus the lateral stopping distance of its closing speed across the road, and
  pushes only across it (no component along s): the ego can pass it. What is nearest to the ego's
  rear half (behind its centre) and is left behind (not faster along the ego's heading) pushes only
  along the road: the car turns about its centre to move sideways, which swings the rear half
  towards it; a car coming up from behind still pushes it across.
* **Velocity**: the ego moves along F (direction F/|F|) at ``min(cruise, |F| * cruise / F_att_max,
  v_safe, v_curve)``: at the potential's minimum it stops; ``v_curve`` is the speed for the road
  ahead (SPEC §5: sqrt(a_lat / |kappa|) within braking distance, RouteFrame.curve_speed_limit). ``v_safe`` is a speed governor: the speed from
  which the ego can stop behind whatever is in its corridor ahead even if that brakes to a stop,
  ``sqrt(v_lead^2 + 2 b (gap - s0))``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.actuation.kinematic import REVERSE_BELOW_MPS, STOP_WISH_MPS
from sumo_avoid.control.apf.potential import attraction, repulsion, unit_and_norm
from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.control.road_view import FrenetScene, RoadView
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.geometry import (
    box_gap,
    convex_distance,
    footprint_corners,
)
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.road.gaps import lane_change_length_m

VRU_STAND_MPS = 0.5  # a person or cyclist slower than this stands (passed at a crawl when only its margin is in the way), m/s


@dataclass(frozen=True)
class ApfParams:
    k_att: float = field_doc(1.0, doc="attraction gain K_att, 1/s (force in m/s units)")
    d_att_m: float = field_doc(10.0, doc="attraction is capped beyond this distance d, m")
    k_rep: float = field_doc(300.0, doc="vehicle/obstacle repulsion gain K_rep, m^3/s")
    rho0_min_m: float = field_doc(2.0, doc="influence distance of an obstacle in the ego's strip at standstill, m")
    rho0_beside_m: float = field_doc(1.0, doc="influence distance of a vehicle beside the ego's strip that does "
                                              "not close across the road (lane-centred neighbours on 3.2 m lanes "
                                              "are 1.4 m apart), m")
    rho0_decel_mps2: float = field_doc(4.0, doc="braking used for the influence distance, m/s^2")
    rho0_headway_s: float = field_doc(0.8, doc="time headway added to the influence distance ahead, s")
    k_edge: float = field_doc(2.0, doc="road-edge and solid-line repulsion gain, m^3/s")
    rho0_edge_m: float = field_doc(0.8, doc="road-edge and solid-line influence distance, m")
    edge_lat_decel_mps2: float = field_doc(2.0, doc="lateral deceleration for the edge influence distance, m/s^2")
    edge_reaction_s: float = field_doc(0.5, doc="reaction time added to the edge influence distance, s")
    lookahead_min_m: float = field_doc(15.0, doc="smallest carrot distance along the route, m")
    lookahead_time_s: float = field_doc(1.5, doc="carrot distance per unit speed, s")
    sense_radius_m: float = field_doc(100.0, doc="obstacles farther than this are ignored, m")
    vru_margin_m: float = field_doc(1.0, doc="a person or cyclist (ground truth) counts as grown by this much on "
                                             "every side: the ego keeps this much more room to it than to a car, m")
    gov_decel_mps2: float = field_doc(4.0, doc="speed governor: braking it plans with, m/s^2")
    gov_standstill_m: float = field_doc(2.0, doc="speed governor: gap kept at standstill, m")
    gov_margin_m: float = field_doc(0.4, doc="speed governor: lateral margin of the corridor ahead, m")
    squeeze_speed_mps: float = field_doc(2.0, doc="speed past a standing vehicle in the governor's strip that the "
                                         "ego can steer clear of (and of such a vehicle), m/s")
    squeeze_closing_mps: float = field_doc(0.2, doc="such a vehicle closing across the road faster than this "
                                           "blocks the strip instead, m/s")
    squeeze_clear_m: float = field_doc(0.1, doc="lateral clearance the ego must be able to reach to pass it, m")
    max_course_deg: float = field_doc(35.0, doc="moving forward, the commanded direction stays within this angle of the road's, deg")
    creep_align_mps: float = field_doc(1.0, doc="moving forward slower than this, the commanded direction turns towards the "
                                                "road's (along it below 0.3 of this), m/s")
    max_lat_speed_mps: float = field_doc(1.5, doc="moving forward, the commanded speed across the road stays below this, m/s")
    curve_lat_accel_mps2: float = field_doc(2.5, doc="speed for the road ahead: lateral acceleration in bends, m/s^2")
    curve_decel_mps2: float = field_doc(3.0, doc="speed for the road ahead: braking before a bend, m/s^2")


@dataclass(frozen=True)
class Field:
    """Potential and force at candidate ego positions (C of them), plus the governor's speed."""

    U: np.ndarray  # (C,)
    F: np.ndarray  # (C, 2)
    v_safe: float  # m/s, for the first candidate (the ego's real position)


class ApfDriver:
    """The APF road field for the egos it is given (each in its route frame, a
    :class:`~sumo_avoid.control.road_view.RoadView` per ego): the carrot, the field, the speed
    governor and the commanded velocity. Driven by :class:`ApfController`, APF-SA
    (:mod:`.apf_sa`) and the formation's members on a road (:mod:`sumo_avoid.control.formation.lane_plan`)."""

    def __init__(self, params: ApfParams, ctx):
        self.p = params
        self.max_course = np.radians(params.max_course_deg)
        self.step_s = float(ctx.step_s)
        self.steering = (float(ctx.turn_radius_m), float(ctx.yaw_rate_radps))  # the drivable line, the speed in turns (RoadView)
        self.views: dict[str, RoadView] = {}

    def add_ego(self, task: EgoTask) -> None:
        self.views[task.vid] = RoadView(task, *self.steering)

    def remove_ego(self, vid: str) -> None:
        self.views.pop(vid, None)

    # --- targets (Frenet) ------------------------------------------------------------------
    def lookahead(self, speed: float) -> float:
        return max(self.p.lookahead_min_m, self.p.lookahead_time_s * abs(speed))

    def carrot(self, view: RoadView, sc: FrenetScene, lateral_offset: float = 0.0, within_m: float = np.inf) -> np.ndarray:
        """(s, d) the attraction pulls towards (at most ``within_m`` ahead: a lateral move to finish by then); an
        offset target lies inside the lanes where it lies (:meth:`RoadView.inside`)."""
        ahead = min(self.lookahead(float(np.hypot(*sc.vel))), within_m)
        if np.hypot(*(view.goal - sc.q)) <= ahead and lateral_offset == 0.0:
            return view.goal
        s_c = min(sc.s + ahead, view.length_m)
        return np.array([s_c, view.inside(s_c, lateral_offset, 0.5 * sc.width) if lateral_offset != 0.0 else 0.0])

    def scene(self, obs: Observation, row: int, vid: str) -> FrenetScene:
        return self.views[vid].scene(obs, row, self.p.sense_radius_m, self.p.vru_margin_m)

    # --- the field (Frenet) ----------------------------------------------------------------
    def field(self, sc: FrenetScene, q_cand: np.ndarray, target: np.ndarray, heading: float | None = None) -> Field:
        """Potential, force and governor speed for the ego placed at ``q_cand`` (C,2) in (s, d)
        (with its own relative heading, or ``heading`` in rad)."""
        p = self.p
        q_cand = np.atleast_2d(np.asarray(q_cand, float))
        C = len(q_cand)
        h = sc.heading if heading is None else heading
        L, W, v_ego = sc.length, sc.width, sc.vel
        hd = np.array([np.cos(h), np.sin(h)])
        U, F = attraction(q_cand, target, p.k_att, p.d_att_m)
        ego_corners = footprint_corners(q_cand, np.full(C, h), np.full(C, L), np.full(C, W))  # (C,4,2)

        v_safe = np.inf
        O = len(sc.o_pos)
        if O:
            oc = footprint_corners(sc.o_pos, sc.o_heading, sc.o_length, sc.o_width)
            P = np.repeat(ego_corners, O, axis=0)
            Q = np.tile(oc, (C, 1, 1))
            rho, p_ego, p_obs = convex_distance(P, Q)
            centre_dir, _ = unit_and_norm(np.repeat(q_cand, O, axis=0) - np.tile(sc.o_pos, (C, 1)))
            away, n = unit_and_norm(p_ego - p_obs)
            away = np.where((n > 1e-6)[:, None], away, centre_dir)
            towards = -away
            cos_phi = np.maximum(towards @ hd, 0.0)
            v_rel = v_ego[None, :] - np.tile(sc.o_vel, (C, 1))
            closing = np.maximum(np.einsum("ij,ij->i", v_rel, towards), 0.0)
            # a vehicle beside the ego's lane strip (no overlap across the road, e.g. oncoming in
            # its own lane, or slower in the next lane) is felt from its closing speed across the
            # road only: passing it is no threat, drifting towards it is; a standing one the ego can
            # steer clear of in time within its lanes is passed the same way, at a crawl (_beside)
            beside, crawl, away, move, lat_closing = self._beside(sc, q_cand, h, ego_corners, oc, v_rel, away)
            # one beside, or apart across the road from an ego turned away from it, pushes from the gap to the ego aligned
            # with the road: turning away swings the rear corner towards it, and counted so the push grew as the car turned,
            # until it stood 0.4 rad askew (bologna_signals seed 2, junction 1c: a car passing on its left, people at the kerb)
            half = 0.5 * np.array([L, W])
            gap, to_ego = box_gap(np.repeat(q_cand - half, O, axis=0), np.repeat(q_cand + half, O, axis=0),
                                  np.tile(oc.min(axis=1), (C, 1)), np.tile(oc.max(axis=1), (C, 1)))
            apart = (to_ego[:, 1] != 0.0) & (beside | (h * to_ego[:, 1] > 0.0))  # turned away: h the sign of to_ego's d
            beside, rho, away = beside | apart, np.where(apart, gap, rho), np.where(apart[:, None], to_ego, away)
            # its influence distance is the clearance kept beside a car plus the lateral stopping
            # distance of its closing speed: the ego's own speed (the headway term, for following)
            # does not count, so a lane-centred car in the next lane does not push the ego at all
            rho0 = np.where(beside, p.rho0_beside_m + move + lat_closing**2 / (2 * p.rho0_decel_mps2),
                            p.rho0_min_m + cos_phi * (closing**2 / (2 * p.rho0_decel_mps2)
                                                      + p.rho0_headway_s * np.hypot(*v_ego)))
            # a person standing (or walking along) behind the kerb beside the strip is felt like the kerb it
            # stands at (its gain and reach): SUMO puts people waiting at a corner at the walking area's edge,
            # at junctions up to 0.2 m into the lane, and its full push swung the ego at 1.5 m/s into a car
            # standing in the oncoming lane, where it stopped on the crossing for good (Uberlandia, 9013072432)
            kerb = beside & np.tile(sc.kerb_only, C)
            rho0 = np.where(kerb, np.minimum(rho0, p.rho0_edge_m), rho0)
            Ur, Fr = repulsion(rho, away, rho0, np.where(kerb, p.k_edge, p.k_rep))
            Fr[:, 0] = np.where(beside, 0.0, Fr[:, 0])  # ... and pushes only across it, never back
            # a car moves sideways only by turning, and turning swings its rear half the other way:
            # what is nearest to the rear half and left behind (not faster along the ego's heading)
            # pushes it along the road only, never across; one coming up from behind still pushes it
            # away across the road (at speed the car moves over more than its rear swings)
            rear = ((p_ego - np.repeat(q_cand, O, axis=0)) @ hd) < 0.0
            left_behind = (-v_rel) @ hd <= 0.0
            Fr[:, 1] = np.where(rear & left_behind, 0.0, Fr[:, 1])
            U = U + Ur.reshape(C, O).sum(axis=1)
            F = F + Fr.reshape(C, O, 2).sum(axis=1)
            v_safe = self._governor(q_cand[0], hd, L, W, oc, sc.o_vel, crawl[:O])

        U, F = self._bounds(sc, q_cand, U, F)
        return Field(U, F, float(v_safe))

    def _bounds(self, sc: FrenetScene, q_cand: np.ndarray, U: np.ndarray, F: np.ndarray):
        """U, F plus the push of the bounds of the ego's lanes on the candidates (C of them)."""
        p, C, L, W, v_ego = self.p, len(q_cand), sc.length, sc.width, sc.vel
        # the bounds of the ego's lanes, one line on each side, repel across the road (always
        # inwards: a car past a bound is pushed back, never further out) from the footprint's
        # corner nearest to each, with the bound taken at that corner's s
        strip = footprint_corners(q_cand, np.zeros(C), np.full(C, L), np.full(C, W))  # aligned with the road
        lo, hi = sc.corridor(strip[..., 0].ravel())
        cd = strip[..., 1].ravel()
        lo_here, hi_here = sc.corridor(np.array([sc.s]))
        # beside a car centred on its lane, m; junction widening only as far as it lies on both sides (where a kerb
        # stops it on one, the car on its lane felt that kerb and was pushed towards the oncoming lane inside the
        # junction, into a bus there: bologna_bus_lane, seed 2)
        room = max(0.5 * (float(hi_here[0] - lo_here[0]) - sc.one_sided_m - W), 0.1)
        for rho, inward in (((cd - lo).reshape(C, 4).min(axis=1), 1.0), ((hi - cd).reshape(C, 4).min(axis=1), -1.0)):
            closing = max(-inward * float(v_ego[1]), 0.0)  # a car drifting towards the bound feels it earlier
            rho0 = p.rho0_edge_m + closing**2 / (2.0 * p.edge_lat_decel_mps2) + p.edge_reaction_s * closing
            rho0 = min(rho0, 0.8 * room)  # in a narrow lane a centred car feels neither bound
            Ur, Fr = repulsion(rho, np.tile([0.0, inward], (C, 1)), np.full(C, rho0), p.k_edge, rho_floor=0.05)
            U, F = U + Ur, F + Fr
        return U, F

    def _beside(self, sc: FrenetScene, q_cand, h: float, ego_corners, oc, v_rel, away):
        """Per (candidate, vehicle) pair, (C*O,) each: which vehicles are beside the ego's strip (incl. those
        squeezed past), which the governor passes at a crawl, the push direction ``away`` (across the road
        for a squeeze the ego must move over for), the extra influence reach ``move`` that move takes, m, and
        the closing speed across the road, m/s."""
        p, C, O = self.p, len(q_cand), len(sc.o_pos)
        e_lo, e_hi = np.repeat(ego_corners[..., 1].min(1), O), np.repeat(ego_corners[..., 1].max(1), O)
        o_lo, o_hi = np.tile(oc[..., 1].min(1), C), np.tile(oc[..., 1].max(1), C)
        side = np.sign(np.tile(sc.o_pos[:, 1], C) - np.repeat(q_cand[:, 1], O))
        lat_closing = np.maximum(v_rel[:, 1] * side, 0.0)
        beside = (e_lo - p.gov_margin_m > o_hi) | (e_hi + p.gov_margin_m < o_lo)
        # the ego's d span taken as aligned with the road (for a squeeze and a VRU beside: turned away from the
        # vehicle, its rear corner swings towards it)
        a_lo, a_hi = np.repeat(q_cand[:, 1], O) - 0.5 * sc.width, np.repeat(q_cand[:, 1], O) + 0.5 * sc.width
        passable, shift = self._squeeze(sc, q_cand, oc, (a_lo, a_hi), (o_lo, o_hi), side, lat_closing)
        squeeze = ~beside & passable
        o_speed = np.tile(np.hypot(*sc.o_vel.T), C)
        slow = o_speed <= p.squeeze_speed_mps
        crawl = squeeze | (slow & self._turned_towards(h, beside, side, (e_lo, e_hi), (o_lo, o_hi), lat_closing))
        # a person or cyclist standing beside the strip, in it only by its margin: passed at a crawl, not waited
        # for (berlin_eastbound, radar, seed 2: a cyclist queued in the next lane behind a parked car, 0.57 m
        # from the ego's side, stopped it for good, and the cyclist waited for the ego to pass)
        grow = sc.o_grow if sc.o_grow is not None else np.zeros(O)
        standing = o_speed < VRU_STAND_MPS
        # (the ego taken as aligned with the road, as for a squeeze: turned, it stood for good with its front in
        # the margin, berlin_eastbound, truth, seed 2)
        body_lo, body_hi = sc.body_span()
        vru_beside = ~beside & np.tile(grow > 0.0, C) & standing & (lat_closing <= p.squeeze_closing_mps) & (
            (a_lo - p.gov_margin_m > np.tile(body_hi, C)) | (a_hi + p.gov_margin_m < np.tile(body_lo, C)))
        crawl = crawl | vru_beside
        beside = beside | squeeze | vru_beside
        # one squeezed past that the ego must move over for (shift > 0) pushes straight across the road,
        # away from it (its corner just ahead of the ego's front face is nearest along the road, and along
        # the road it pushes no car beside it), from as far as the car needs to move over by the shift at
        # its turning radius (wildau_turns: a left-turner waiting inside the junction 0.24 m into the ego's
        # strip pushed only within 1 m, the ego crawled up to it without moving over and stood there for
        # good); one it clears already is passed as before (pushed across it swerved the ego towards a
        # bus in the oncoming lane: bologna_bus_lane, radar, seed 3, a person's box at the kerb)
        over = squeeze & (shift > 0.0)
        away = np.where(over[:, None], np.column_stack([np.zeros(C * O), -side]), away)
        move = np.zeros(C * O)
        move[over] = [lane_change_length_m(x, self.steering[0]) for x in shift[over]]
        return beside, crawl, away, move, lat_closing

    def _squeeze(self, sc: FrenetScene, q_cand, oc, e_span, o_span, side, lat_closing):
        """((C*O,) bool, (C*O,) shift, m): the vehicle stands (or crawls) and does not close across the road, and the
        ego, taken as aligned with the road (like for the bounds: a heading turned away from the
        vehicle must not make its rear corner count), clears it with ``squeeze_clear_m`` by a small
        sideways shift (<= ``gov_margin_m``) that keeps it in its lanes and that it can make before
        reaching it (shift <= gap ahead x tan(max_course)).
        Such a vehicle is passed at a crawl while its push widens the gap: a car waiting at the
        oncoming lane's stop line with its nose turned in, just ahead of the ego's corner and to its
        side, would otherwise stop the ego for good inside a junction while it waits for the ego."""
        p, C, O, L = self.p, len(q_cand), len(sc.o_pos), sc.length
        qs = np.repeat(q_cand[:, 0], O)
        e_lo, e_hi = e_span  # the ego's d span aligned with the road, (C*O,) each
        o_lo, o_hi = o_span  # the vehicles' d spans, (C*O,) each, as field() has them
        shift = np.where(side > 0, e_hi - o_lo, o_hi - e_lo) + p.squeeze_clear_m
        lo, hi = sc.corridor(q_cand[:, 0])
        room = np.where(side > 0, e_lo - shift >= np.repeat(lo, O), e_hi + shift <= np.repeat(hi, O))
        gap = np.tile(oc[..., 0].min(1), C) - (qs + 0.5 * L)
        in_time = (shift <= 0.0) | (shift <= np.maximum(gap, 0.0) * np.tan(self.max_course))
        slow = np.tile(np.hypot(*sc.o_vel.T), C) <= p.squeeze_speed_mps
        small = shift <= p.gov_margin_m  # it reaches at most gov_margin - clear into the ego's strip: the
        # shifted ego needs no check against the others (their own pushes keep it off them)
        return slow & small & (lat_closing <= p.squeeze_closing_mps) & room & in_time, shift

    def _turned_towards(self, h: float, beside, side, e_span, o_span, lat_closing) -> np.ndarray:
        """(C*O,) bool: a standing (or crawling) vehicle -- a person waiting at the kerb -- beside the
        ego's strip that the governor's strip, straight along the ego's heading, catches because the
        heading is turned towards it: the car turns back to the road's direction within R (1 - cos h)
        sideways (its turning radius R); where it keeps ``squeeze_clear_m`` after that, the governor
        passes it at ``squeeze_speed_mps`` instead of stopping for good (Bologna corner 1c: turned
        4.6 degrees, it stood 35 s on a crossing 0.5 m from people waiting at its end)."""
        p = self.p
        e_lo, e_hi = e_span
        o_lo, o_hi = o_span
        clear = np.where(side > 0, o_lo - e_hi, e_lo - o_hi)
        realign = np.where(np.sign(h) == side, self.steering[0] * (1.0 - np.cos(h)), 0.0)
        return beside & (clear - realign >= p.squeeze_clear_m) & (lat_closing <= p.squeeze_closing_mps)

    def _governor(self, q, hd, L, W, corners, vel, squeeze) -> float:
        """The speed from which the ego stops behind anything in its strip ahead (``squeeze``
        (O,) bool: vehicles passed at ``squeeze_speed_mps`` instead, reached at that speed: from afar
        the ego approaches at the speed from which it slows to it in time)."""
        nd = np.array([-hd[1], hd[0]])
        rel = corners - q
        x = rel @ hd  # (O,4)
        y = rel @ nd
        half = 0.5 * W + self.p.gov_margin_m
        ahead = (y.max(axis=1) >= -half) & (y.min(axis=1) <= half) & (x.max(axis=1) > 0.5 * L)
        sq = ahead & squeeze  # passed at squeeze speed: reached at that speed, braking at gov_decel_mps2
        v_squeeze = (float(np.sqrt(self.p.squeeze_speed_mps**2 + 2.0 * self.p.gov_decel_mps2 *
                                   np.maximum(x[sq].min(axis=1) - 0.5 * L, 0.0)).min()) if sq.any() else np.inf)
        ahead &= ~squeeze
        if not ahead.any():
            return v_squeeze
        gap = np.maximum(x[ahead].min(axis=1) - 0.5 * L, 0.0)
        v_lead = np.maximum(vel[ahead] @ hd, 0.0)
        free = np.maximum(gap - self.p.gov_standstill_m, 0.0)
        return float(min(np.sqrt(v_lead**2 + 2.0 * self.p.gov_decel_mps2 * free).min(), v_squeeze))

    def velocity(self, fld: Field, cruise: float, v_road: float = np.inf, speed_mps: float = np.inf,
                 may_reverse: bool = True) -> np.ndarray:
        """(s_dot, d_dot) along F at min(cruise, |F| cruise / F_att_max, v_safe, v_road); forward, the
        direction is kept within ``max_course_deg`` of the road's (the field's sideways pull of a
        wall its corner touches would otherwise ask a car to turn on the spot); a field that points
        back along the road (F_s <= 0) is followed (a moving car brakes; a standing one reverses) except by a
        car standing (``speed_mps``) that may not reverse (``may_reverse``): it stands."""
        F = fld.F[0]
        mag = np.hypot(*F)
        if mag < 1e-9:
            return np.zeros(2)
        f_max = self.p.k_att * self.p.d_att_m
        speed = min(cruise, mag * cruise / f_max, fld.v_safe, v_road)
        course = np.arctan2(F[1], F[0])
        if F[0] <= 0.0:
            # the field pushes it back: moving, the car brakes (and steers towards it); standing, the
            # actuator would reverse it towards it -- only where it may (``may_reverse``: it sees behind
            # and nothing is there; a front radar alone does not see the car queued behind it, Bologna)
            if not may_reverse and speed_mps <= REVERSE_BELOW_MPS:
                return np.zeros(2)
            return speed * np.array([np.cos(course), np.sin(course)])
        # a car going forward steers at most max_course off the road's direction and moves across
        # it at most at max_lat_speed: a wall a corner touches must not turn it sideways
        # creeping (slower than creep_align_mps) it turns towards the road's direction, straight below 0.3 of it:
        # a car creeping in a queue gains no room across the road, its heading only turns (Uberlandia, edge
        # 299472281#2: 0.35 rad in 2 m behind a cyclist, a car passing in the next lane clipped its rear corner)
        creep = np.clip((speed / max(self.p.creep_align_mps, 1e-9) - 0.3) / 0.7, 0.0, 1.0)
        lim = self.max_course * (creep if speed >= STOP_WISH_MPS else 1.0)
        course = np.clip(course, -lim, lim)
        if speed < STOP_WISH_MPS:  # stopping: brake facing the course (in a bend, steering with the road; a
            # car braking with its wheels straight went on straight, 1.4 m towards an oncoming bus inside a
            # junction: bologna_bus_lane, radar, seed 2)
            return 0.1 * STOP_WISH_MPS * np.array([np.cos(course), np.sin(course)])
        v = speed * np.array([np.cos(course), np.sin(course)])
        v[1] = np.clip(v[1], -self.p.max_lat_speed_mps, self.p.max_lat_speed_mps)
        return v

    def road_speed(self, view: RoadView, sc: FrenetScene) -> float:
        return view.curve_speed(sc.s, self.p.curve_lat_accel_mps2, self.p.curve_decel_mps2)

class ApfController(BaseController):
    """Plain potential field (no escape from local minima), in each ego's route frame."""

    def __init__(self, params: ApfParams, ctx):
        super().__init__(params, ctx)
        self.driver = ApfDriver(params, ctx)

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        self.driver.add_ego(task)

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        self.driver.remove_ego(vid)

    def act(self, obs: Observation) -> np.ndarray:
        drv = self.driver
        out = np.zeros((len(obs.ego_ids), 2))
        for k, (vid, row) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            task, view = self.tasks[vid], drv.views[vid]
            sc = drv.scene(obs, row, vid)
            offset, v_lane = view.lane_change(sc, drv.lookahead(float(np.hypot(*sc.vel))), self.p.gov_decel_mps2,
                                              drv.step_s)  # the path's lane changes wait for a gap
            fld = drv.field(sc, sc.q[None, :], drv.carrot(view, sc, offset))
            v = drv.velocity(fld, task.cruise_speed_mps, min(drv.road_speed(view, sc), v_lane))
            out[k] = view.to_xy_velocity(sc.s, sc.d, v, drv.step_s)
        return out
