"""Flocking on roads (issue 14 item 9): SPEC §1's terms computed in each ego's route frame (SPEC §5).

On a road scenario (no ``[arena]``) every flock member gets its own route frame
(:class:`~sumo_avoid.control.road_view.RoadView`: s along its route's reference path, d across it,
positive left). Per ego and update, everything it senses is mapped into that frame, the terms of
eq. 1-10 are summed there, and the result is mapped back to the plane:

* **Migration** along the route: the self-propulsion is v_flock (1, 0) in (s, d) (eq. 9 with
  v̂_i = the route's tangent instead of the own velocity's direction), so a bend, a ramp or a
  turn is straight to the flock.
* **Neighbours** (eq. 1-6): the flock mates' positions and velocities in the ego's frame.
* **Walls** (eq. 7-8): the edges of the carriageway, the lanes of the route's direction
  (:class:`Carriageway`): one shill on each side, at distance from the footprint's corner nearest
  to that bound (the bound taken at the corner's s), velocity v_shill across the road, inwards.
  A footprint past a bound has distance 0 (full correction, SPEC §1).
* **Obstacles**: the other vehicles' (and static obstacles') footprints mapped into the frame, one
  shill each at distance footprint to footprint, from the obstacle's nearest point towards the
  ego's; a vehicle wholly outside the carriageway (oncoming traffic, the exit after the diverge,
  a road nearby) is left out, as in :class:`RoadView`'s scene.
* **Speed for the road ahead** (SPEC §5): the desired speed is also cut at
  √(a_lat / |κ|) within the braking envelope (:meth:`RoadView.curve_speed`).

docs/flocking.md has the formulas and what was measured.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.control.flock_terms import (
    FlockingParams,
    combine,
    friction,
    repulsion,
    shill,
)
from sumo_avoid.control.road_view import MAX_ABS_D_M, OUTSIDE_MARGIN_M, RoadView
from sumo_avoid.core.curves import braking_curve_D as D
from sumo_avoid.core.geometry import convex_distance, footprint_corners, wrap_angle
from sumo_avoid.core.types import EgoTask, LanePiece

#: Lanes that do not go on to the next edge of the route end in a taper over this length, m.
TAPER_M = 30.0
_EPS = 1e-6


def _edge_bounds(offsets, widths) -> np.ndarray:
    o, w = np.asarray(offsets, float), np.asarray(widths, float)
    return np.array([(o - 0.5 * w).min(), (o + 0.5 * w).max()])


class Carriageway:
    """The flock's walls along one route: d_lo(s) <= d <= d_hi(s), all lanes of the route's direction.

    Unlike :class:`~sumo_avoid.core.lanes.RouteLanes` (one car keeps its path's lane, so the other
    lanes taper to it before a junction) a flock spreads over every lane that goes on: before a
    junction the bounds taper over the last min(``TAPER_M``, half the edge) from the edge's lanes
    to the part of them the next edge's lanes continue (the intersection of both, in the path's d);
    through the junction they widen linearly to the next edge's lanes. Piecewise linear in s.
    """

    def __init__(self, pieces: tuple[LanePiece, ...]):
        normal = [k for k, p in enumerate(pieces) if not p.edge.startswith(":")]
        pts: list[tuple[float, np.ndarray]] = []
        for n, k in enumerate(normal):
            p = pieces[k]
            b0, b1 = _edge_bounds(p.offsets_start_m, p.widths_m), _edge_bounds(p.offsets_end_m, p.widths_m)
            a, b = p.s_start_m, p.s_end_m
            pts.append((a, b0))
            if n + 1 == len(normal):
                pts.append((b, b1))
                continue
            q = pieces[normal[n + 1]]
            nxt = _edge_bounds(q.offsets_start_m, q.widths_m)
            end = np.array([max(b1[0], nxt[0]), min(b1[1], nxt[1])])  # the lanes that go on
            if end[1] - end[0] < 1e-3:  # the next edge's lanes lie beside the last ones: keep the path's own
                end = nxt
            t0 = max(a, b - min(TAPER_M, 0.5 * (b - a)))
            f = (t0 - a) / (b - a) if b - a > _EPS else 0.0
            pts += [(t0, (1 - f) * b0 + f * b1), (b, end)]
        if not pts:  # a path of internal lanes only
            pts = [(p.s_start_m, _edge_bounds(p.offsets_start_m, p.widths_m)) for p in pieces]
            pts.append((pieces[-1].s_end_m, _edge_bounds(pieces[-1].offsets_end_m, pieces[-1].widths_m)))
        s = np.array([q[0] for q in pts])
        self._s = np.maximum.accumulate(s + _EPS * np.arange(len(s)))  # strictly increasing
        self._lo = np.array([q[1][0] for q in pts])
        self._hi = np.array([q[1][1] for q in pts])

    def corridor(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(d_lo (N,), d_hi (N,)) at arc lengths s, m."""
        s = np.atleast_1d(np.asarray(s, float))
        return np.interp(s, self._s, self._lo), np.interp(s, self._s, self._hi)


def road_boxes(centres, length, width) -> np.ndarray:
    """Footprints (N,4,2) in (s, d) of vehicles aligned with the road (flock mates: V2V sends no heading)."""
    return footprint_corners(centres, np.zeros(len(centres)), length, width)


def safety_caps(v, own, walls, boxes, p: FlockingParams) -> np.ndarray:
    """The desired velocity (s_dot, d_dot) with the model's braking curve D(r, a_shill, p_shill) as
    hard bounds, so that the sum of the terms never drives into a bound or a vehicle:

    * along the road: s_dot <= max(s_dot_o, 0) + D(gap - road_gap_m) for every footprint o ahead
      that overlaps the ego's strip across the road (gap: rear of o minus front of the ego), and
      s_dot <= D(distance to the route's end - r0_shill);
    * across it, for every footprint o beside (overlapping the ego's extent along the road): the
      speed towards it at most d_dot_o + D(gap - r0_shill);
    * across it, last (the road wins): d_dot >= -D(rho_right - wall_margin), d_dot <= D(rho_left -
      wall_margin), rho the footprint's distance to each bound (0 past it: never further out).

    own (4,2) the ego's footprint in (s, d); walls (3,) distances to the right and left bound and
    the route's end; boxes: [(footprints (B,k,2), velocities (B,2))] of everything else.
    """
    a, g, r0, m = p.a_shill_mps2, p.p_shill_ps, p.r0_shill_m, p.wall_margin_m
    rear, front, lo, hi = own[:, 0].min(), own[:, 0].max(), own[:, 1].min(), own[:, 1].max()
    boxes = [(b, u) for b, u in boxes if len(b)]
    ext = np.concatenate([np.stack([b[..., 0].min(1), b[..., 0].max(1), b[..., 1].min(1), b[..., 1].max(1)], 1)
                          for b, _ in boxes]) if boxes else np.zeros((0, 4))
    vel = np.concatenate([u for _, u in boxes]) if boxes else np.zeros((0, 2))
    o_rear, o_front, o_lo, o_hi = ext.T
    ahead = (o_hi > lo) & (o_lo < hi) & (o_rear > 0.5 * (rear + front))
    beside = (o_front > rear) & (o_rear < front)
    left, right = beside & (o_lo >= 0.5 * (lo + hi)), beside & (o_hi <= 0.5 * (lo + hi))
    r = np.concatenate([[walls[0] - m, walls[1] - m, walls[2] - r0], o_rear[ahead] - front - p.road_gap_m,
                        o_lo[left] - hi - r0, lo - o_hi[right] - r0])
    speed = D(r, a, g)  # one call: the braking curve at every distance
    n1, n2 = 3 + int(ahead.sum()), 3 + int(ahead.sum()) + int(left.sum())
    cap_s = min(speed[2], float(np.min(np.maximum(vel[ahead, 0], 0.0) + speed[3:n1], initial=np.inf)))
    cap_hi = float(np.min(vel[left, 1] + speed[n1:n2], initial=np.inf))
    cap_lo = float(np.max(vel[right, 1] - speed[n2:], initial=-np.inf))
    vs, vd = min(float(v[0]), cap_s), float(v[1])
    if cap_lo <= cap_hi:
        vd = min(max(vd, cap_lo), cap_hi)
    return np.array([vs, min(max(vd, -speed[0]), speed[1])])


def course_limits(v, p: FlockingParams) -> np.ndarray:
    """A car's limits on the desired (s_dot, d_dot): |d_dot| <= max_lat_speed and, forward,
    |d_dot| <= tan(max_course) s_dot (it cannot move sideways; a stopped car stays put)."""
    lat = min(p.max_lat_speed_mps, np.tan(np.radians(p.max_course_deg)) * max(float(v[0]), 0.0))
    return np.array([v[0], np.clip(v[1], -lat, lat)])


class RoadFlock:
    """The route frames and carriageways of a flock's members; maps their senses into each frame."""

    def __init__(self, step_s: float):
        self.step_s = float(step_s)
        self.views: dict[str, RoadView] = {}
        self.ways: dict[str, Carriageway | None] = {}

    def add(self, task: EgoTask) -> None:
        self.views[task.vid] = RoadView(task)
        self.ways[task.vid] = Carriageway(task.lanes) if task.lanes else None

    def remove(self, vid: str) -> None:
        self.views.pop(vid, None)
        self.ways.pop(vid, None)

    def corridor(self, vid: str, s) -> tuple[np.ndarray, np.ndarray]:
        way = self.ways[vid]
        if way is None:
            s = np.atleast_1d(np.asarray(s, float))
            return np.full(len(s), -np.inf), np.full(len(s), np.inf)
        return way.corridor(s)

    def frame_state(self, vid: str, pos, vel, heading: float):
        """Own (s, d), velocity (s_dot, d_dot) and heading relative to the path."""
        view = self.views[vid]
        s, d = view.locate(pos)
        vs, vd = view.frame.velocity_to_frenet(s, d, np.asarray(vel, float)[None, :])
        psi = float(wrap_angle(heading - view.frame.heading_at(s)[0]))
        return s, d, np.array([vs[0], vd[0]]), psi

    def to_frame(self, vid: str, s: float, pos, vel, window_m: float):
        """Points (N,2) and their velocities (N,2) in ``vid``'s frame (projected near s)."""
        frame = self.views[vid].frame
        if not len(pos):
            return np.zeros((0, 2)), np.zeros((0, 2))
        ps, pd = frame.to_frenet(pos, np.full(len(pos), s), window_m)
        vs, vd = frame.velocity_to_frenet(ps, pd, vel)
        return np.column_stack([ps, pd]), np.column_stack([vs, vd])

    def obstacles(self, vid: str, s: float, corners, vel, window_m: float):
        """Footprints (B,4,2) in the plane -> (corners (B',4,2), velocities (B',2)) in the frame,
        without those wholly outside the carriageway or too far across or along it."""
        if not len(corners):
            return np.zeros((0, 4, 2)), np.zeros((0, 2))
        frame = self.views[vid].frame
        c = np.asarray(corners, float)
        k = c.shape[1]
        cs, cd = frame.to_frenet(c.reshape(-1, 2), np.full(c.shape[0] * k, s), window_m)
        fc = np.stack([cs, cd], -1).reshape(-1, k, 2)
        lo, hi = self.corridor(vid, cs)
        lo, hi = lo.reshape(-1, k), hi.reshape(-1, k)
        inside = ((fc[..., 1] > lo - OUTSIDE_MARGIN_M).any(1) & (fc[..., 1] < hi + OUTSIDE_MARGIN_M).any(1)
                  & (np.abs(fc[..., 1]).min(1) < MAX_ABS_D_M) & (np.abs(fc[..., 0] - s).min(1) < window_m)
                  & np.isfinite(fc).all((1, 2)))
        fc = fc[inside]
        centre = fc.mean(axis=1)
        vs, vd = frame.velocity_to_frenet(centre[:, 0], centre[:, 1], np.asarray(vel, float)[inside])
        return fc, np.column_stack([vs, vd])

    def wall_distances(self, vid: str, s: float, d: float, psi: float, length: float, width: float):
        """Distances (3,) of the footprint to the right and left bound and to the end of the route
        (0 past it) and their inward normals (3, 2) in (s, d). The route's end is a wall across the
        road: the flock stops there, a car driven past the end of its route leaves the network."""
        c = footprint_corners(np.array([[s, d]]), np.array([psi]), np.array([length]), np.array([width]))[0]
        lo, hi = self.corridor(vid, c[:, 0])
        end = self.views[vid].length_m
        dist = np.array([(c[:, 1] - lo).min(), (hi - c[:, 1]).min(), end - c[:, 0].max()])
        return np.maximum(dist, 0.0), np.array([[0.0, 1.0], [0.0, -1.0], [-1.0, 0.0]])

    @staticmethod
    def obstacle_distances(s: float, d: float, psi: float, length: float, width: float, polys):
        """Footprint-to-footprint distances (B,) to obstacle polygons (B,k,2) in the frame and unit
        directions (B,2) from each obstacle's nearest point towards the ego (0 in contact; then
        from the obstacle's centre)."""
        own = footprint_corners(np.array([[s, d]]), np.array([psi]), np.array([length]), np.array([width]))
        dist, p_ego, p_obs = convex_distance(np.repeat(own, len(polys), axis=0), polys)
        away = p_ego - p_obs
        n = np.hypot(away[:, 0], away[:, 1])
        centre = np.array([s, d]) - polys.mean(axis=1)
        away = np.where((n > 1e-6)[:, None], away, centre)
        return dist, away / np.maximum(np.hypot(away[:, 0], away[:, 1]), 1e-12)[:, None]

    def to_xy(self, vid: str, s: float, d: float, v_frenet) -> np.ndarray:
        return self.views[vid].to_xy_velocity(s, d, v_frenet, self.step_s)

    def curve_speed(self, vid: str, s: float, a_lat_mps2: float, decel_mps2: float) -> float:
        return self.views[vid].curve_speed(s, a_lat_mps2, decel_mps2)

    def desired(self, p: FlockingParams, ego_ids, own_pos, own_vel, heading, length, width, nb_pos, nb_vel,
                groups) -> np.ndarray:
        """Desired velocities (E,2) in the plane, each computed in its ego's route frame.

        own_* (E,..): the egos' sensed states; nb_pos, nb_vel (E,2): the flock mates' states as
        received (row k: ego k); groups: obstacles as (corners (B,K,2), velocities (B,2), owner (B,)
        or None) in the plane, ``owner`` = the ego that perceives each (radar), None = all do.
        """
        e = len(ego_ids)
        out = np.zeros((e, 2))
        for k, vid in enumerate(ego_ids):
            s, d, v_own, psi = self.frame_state(vid, own_pos[k], own_vel[k], heading[k])
            q, vk = np.array([[s, d]]), v_own[None, :]
            v = np.array([[p.v_flock_mps, 0.0]])  # migration along the route
            mates = np.flatnonzero(np.arange(e) != k)
            nb_fr, nb_v = self.to_frame(vid, s, nb_pos[mates], nb_vel[mates], p.r_c_m)
            r = np.hypot(nb_fr[:, 0] - s, nb_fr[:, 1] - d)
            j = np.flatnonzero(r <= p.r_c_m)
            i = np.zeros(len(j), dtype=np.int64)
            v = v + repulsion(q, nb_fr, i, j, r[j], p, 1) + friction(vk, nb_v, i, j, r[j], p, 1)
            dist_w, inward = self.wall_distances(vid, s, d, psi, length[k], width[k])
            v = v + shill(vk, dist_w[None], inward[None], p)
            ahead_boxes = []
            for corners, vel, owner in groups:
                mine = np.ones(len(corners), bool) if owner is None else owner == k
                gap = np.hypot(corners[..., 0] - own_pos[k, 0], corners[..., 1] - own_pos[k, 1]).min(axis=1)
                mine &= gap <= p.r_c_m
                polys, o_vel = self.obstacles(vid, s, corners[mine], vel[mine], p.r_c_m)
                if len(polys):
                    dist, away = self.obstacle_distances(s, d, psi, length[k], width[k], polys)
                    v = v + shill(vk, dist[None], away[None], p, o_vel[None])
                    ahead_boxes.append((polys, o_vel))
            v = combine(v, p)[0]
            v_road = self.curve_speed(vid, s, p.curve_lat_accel_mps2, p.curve_decel_mps2)
            speed = float(np.hypot(*v))
            if speed > v_road:
                v = v * (v_road / speed)
            own = footprint_corners(q, np.array([psi]), length[k:k + 1], width[k:k + 1])[0]
            mate_boxes = road_boxes(nb_fr[j], length[mates[j]], width[mates[j]])
            ahead = [(mate_boxes, nb_v[j])] + ahead_boxes
            v = safety_caps(course_limits(v, p), own, dist_w, ahead, p)
            out[k] = self.to_xy(vid, s, d, v)
        return out
