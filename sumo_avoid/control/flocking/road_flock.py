"""Flocking on roads: SPEC §1's terms computed in each ego's route frame (SPEC §5).

On a road scenario (no ``[arena]``) every flock member gets its own route frame
(:class:`~sumo_avoid.control.road_view.RoadView`: s along its route's reference path, d across it,
positive left). Per ego and update, everything it senses is mapped into that frame, the terms of
eq. 1-10 are summed there, and the result is mapped back to the plane:

* **Migration** along the route: the self-propulsion is v_flock (1, 0) in (s, d) (eq. 9 with
  v̂_i = the route's tangent instead of the own velocity's direction), so a bend, a ramp or a
  turn is straight to the flock.
* **Neighbours** (eq. 1-6): the flock mates' positions and velocities in the ego's frame.
* **Walls** (eq. 7-8): the edges of the carriageway, the lanes of the route's direction
  (:class:`~sumo_avoid.road.carriageway.Carriageway`): one shill on each side, at distance from the footprint's corner nearest
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

from sumo_avoid.control.flocking.terms import (
    FlockingParams,
    combine,
    pair_terms,
    neighbour_pairs,
    shill,
)
from sumo_avoid.control.road_view import (
    MAX_ABS_D_M,
    OUTSIDE_MARGIN_M,
    TRACK_WINDOW_M,
    RoadView,
)
from sumo_avoid.core.curves import braking_curve_D as D
from sumo_avoid.core.geometry import convex_distance, footprint_corners, wrap_angle
from sumo_avoid.core.types import EgoTask
from sumo_avoid.road.carriageway import Carriageway

def road_boxes(centres, vel, length, width) -> np.ndarray:
    """Footprints (N,4,2) in (s, d) of the flock mates (V2V sends no heading): along their velocity
    (s_dot, d_dot) when they move faster than 1 m/s, else along the road."""
    moving = np.hypot(vel[:, 0], vel[:, 1]) > 1.0
    return footprint_corners(centres, np.where(moving, np.arctan2(vel[:, 1], vel[:, 0]), 0.0), length, width)


def safety_caps(v, own, walls, boxes, p: FlockingParams) -> np.ndarray:
    """The desired velocity (s_dot, d_dot) with the model's braking curve D(r, a_shill, p_shill) as
    hard bounds, so that the sum of the terms never drives into a bound or a vehicle:

    * along the road: s_dot <= sqrt(max(s_dot_o, 0)^2 + D(gap - road_gap_m)^2) for every footprint
      o ahead that overlaps the ego's strip across the road widened by side_gap_m on each side (gap:
      rear of o minus front of the ego; D^2 ~ 2 a_shill gap: the ego stops behind o even if o
      brakes to a stop at a_shill), and s_dot <= D(distance to the route's end - r0_shill);
    * across it, for every footprint o beside (overlapping the ego's extent along the road): the
      speed towards it at most d_dot_o + D(gap - side_gap_m);
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
    g_side = p.side_gap_m
    ahead = (o_hi > lo - g_side) & (o_lo < hi + g_side) & (o_rear > 0.5 * (rear + front))
    beside = (o_front > rear) & (o_rear < front)
    left, right = beside & (o_lo >= 0.5 * (lo + hi)), beside & (o_hi <= 0.5 * (lo + hi))
    r = np.concatenate([[walls[0] - m, walls[1] - m, walls[2] - r0], o_rear[ahead] - front - p.road_gap_m,
                        o_lo[left] - hi - g_side, lo - o_hi[right] - g_side])
    speed = D(r, a, g)  # one call: the braking curve at every distance
    n1, n2 = 3 + int(ahead.sum()), 3 + int(ahead.sum()) + int(left.sum())
    cap_s = min(speed[2], float(np.min(np.hypot(np.maximum(vel[ahead, 0], 0.0), speed[3:n1]), initial=np.inf)))
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
    """The flock's route frames: the members that drive the same route share one frame (the
    first such member's reference path; the carriageway spans every lane across it), so each
    update maps the group's states into it once and sums the terms for all members at once."""

    def __init__(self, step_s: float):
        self.step_s = float(step_s)
        self.key: dict[str, tuple] = {}  # ego id -> its route (the normal edges of its path)
        self.views: dict[tuple, RoadView] = {}  # route -> frame
        self.ways: dict[tuple, Carriageway | None] = {}
        self._s: dict[str, float] = {}  # ego id -> its s at the last update (projection hint)

    def add(self, task: EgoTask) -> None:
        key = tuple(p.edge for p in task.lanes if not p.edge.startswith(":")) or (task.vid,)
        self.key[task.vid] = key
        if key not in self.views:
            self.views[key] = RoadView(task)
            self.ways[key] = Carriageway(task.lanes) if task.lanes else None

    def remove(self, vid: str) -> None:
        self.key.pop(vid, None)
        self._s.pop(vid, None)

    def corridor(self, key, s) -> tuple[np.ndarray, np.ndarray]:
        s = np.asarray(s, float)
        way = self.ways[key]
        if way is None:
            return np.full(s.shape, -np.inf), np.full(s.shape, np.inf)
        lo, hi = way.corridor(s.ravel())
        return lo.reshape(s.shape), hi.reshape(s.shape)

    def _locate(self, frame, ids, pos) -> tuple[np.ndarray, np.ndarray]:
        """(s, d) of the members' centres, each projected near its s of the last update."""
        hint = np.array([self._s.get(v, np.nan) for v in ids])
        s, d = np.empty(len(ids)), np.empty(len(ids))
        known = np.isfinite(hint)
        if known.any():
            s[known], d[known] = frame.to_frenet(pos[known], hint[known], TRACK_WINDOW_M)
        if (~known).any():
            s[~known], d[~known] = frame.to_frenet(pos[~known])
        self._s.update(zip(ids, s.tolist()))
        return s, d

    def _obstacles(self, key, s_near, corners, window_m: float):
        """Footprints (B,K,2) in the plane -> in the frame (B,K,2), projected near ``s_near`` (B,),
        and which are kept: not wholly outside the carriageway, nor too far across or along it."""
        frame = self.views[key].frame
        b, k = corners.shape[:2]
        cs, cd = frame.to_frenet(corners.reshape(-1, 2), np.repeat(s_near, k), window_m)
        fc = np.stack([cs, cd], -1).reshape(b, k, 2)
        lo, hi = self.corridor(key, fc[..., 0])
        keep = ((fc[..., 1] > lo - OUTSIDE_MARGIN_M).any(1) & (fc[..., 1] < hi + OUTSIDE_MARGIN_M).any(1)
                & (np.abs(fc[..., 1]).min(1) < MAX_ABS_D_M) & (np.abs(fc[..., 0] - s_near[:, None]).min(1) < window_m)
                & np.isfinite(fc).all((1, 2)))
        return fc, keep

    def desired(self, p: FlockingParams, ego_ids, own_pos, own_vel, heading, length, width, nb_pos, nb_vel,
                groups) -> np.ndarray:
        """Desired velocities (E,2) in the plane, computed in the members' route frames.

        own_* (E,..): the egos' sensed states; nb_pos, nb_vel (E,2): the flock mates' states as
        received (row k: ego k); groups: obstacles as (corners (B,K,2), velocities (B,2), owner (B,)
        or None) in the plane, ``owner`` = the ego that perceives each (radar), None = all do.
        """
        out = np.zeros((len(ego_ids), 2))
        routes: dict[tuple, list[int]] = {}
        for k, vid in enumerate(ego_ids):
            routes.setdefault(self.key[vid], []).append(k)
        for key, members in routes.items():
            idx = np.asarray(members)
            out[idx] = self._group(key, idx, p, ego_ids, own_pos, own_vel, heading, length, width, nb_pos, nb_vel,
                                   groups)
        return out

    def _group(self, key, idx, p, ego_ids, own_pos, own_vel, heading, length, width, nb_pos, nb_vel, groups):
        view, frame = self.views[key], self.views[key].frame
        m = len(idx)
        s, d = self._locate(frame, [ego_ids[k] for k in idx], own_pos[idx])
        q = np.column_stack([s, d])
        vq = np.column_stack(frame.velocity_to_frenet(s, d, own_vel[idx]))
        psi = wrap_angle(heading[idx] - frame.heading_at(s))
        L, W = length[idx], width[idx]
        v = np.tile([p.v_flock_mps, 0.0], (m, 1))  # migration along the route
        # flock mates (every member's state as received), near the nearest member of this route
        near = np.argmin(np.hypot(*(nb_pos[:, None, :] - own_pos[idx][None]).transpose(2, 0, 1)), axis=1)
        ns, nd = frame.to_frenet(nb_pos, s[near], p.r_c_m)
        nq, nv = np.column_stack([ns, nd]), np.column_stack(frame.velocity_to_frenet(ns, nd, nb_vel))
        i, j, r = neighbour_pairs(q, nq, p.r_c_m, same=False)
        keep = j != idx[i]
        i, j, r = i[keep], j[keep], r[keep]
        rep, fric = pair_terms(q, nq, vq, nv, i, j, r, p, m)
        v = v + rep + fric
        # walls: the carriageway's bounds and the route's end
        own = footprint_corners(q, psi, L, W)  # (M,4,2)
        lo, hi = self.corridor(key, own[..., 0])
        walls = np.maximum(np.stack([(own[..., 1] - lo).min(1), (hi - own[..., 1]).min(1),
                                     view.length_m - own[..., 0].max(1)], 1), 0.0)
        v = v + shill(vq, walls, np.broadcast_to(WALL_NORMALS, (m, 3, 2)), p)
        # obstacles: the other vehicles' (and static obstacles') footprints
        boxes = [[] for _ in range(m)]
        mates = road_boxes(nq, nv, length, width)
        for a in range(m):
            close = j[i == a]
            boxes[a].append((mates[close], nv[close]))
        for corners, vel, owner in groups:
            gap = np.hypot(corners[None, ..., 0] - own_pos[idx, 0, None, None],
                           corners[None, ..., 1] - own_pos[idx, 1, None, None]).min(2)  # (M,B)
            sees = gap <= p.r_c_m
            if owner is not None:
                sees &= owner[None, :] == idx[:, None]
            b = np.flatnonzero(sees.any(0))
            if not len(b):
                continue
            fc, kept = self._obstacles(key, s[np.argmin(gap[:, b], axis=0)], corners[b], p.r_c_m)
            b, fc, sees = b[kept], fc[kept], sees[:, b[kept]]
            if not len(b):
                continue
            centre = fc.mean(axis=1)
            o_vel = np.column_stack(frame.velocity_to_frenet(centre[:, 0], centre[:, 1], vel[b]))
            dist, away = obstacle_distances(own, fc)  # (M,B')
            dist = np.where(sees, dist, np.inf)
            v = v + shill(vq, dist, away, p, np.broadcast_to(o_vel[None], dist.shape + (2,)))
            for a in range(m):
                boxes[a].append((fc[sees[a]], o_vel[sees[a]]))
        v = combine(v, p)
        v_road = frame.curve_speed_limit(s, np.inf, p.curve_lat_accel_mps2, p.curve_decel_mps2)
        speed = np.hypot(v[:, 0], v[:, 1])
        v = v * np.minimum(1.0, v_road / np.maximum(speed, 1e-12))[:, None]
        # the course limits again after the caps: a cap on s_dot must not leave a sideways command
        v = np.array([course_limits(safety_caps(course_limits(v[a], p), own[a], walls[a], boxes[a], p), p)
                      for a in range(m)])
        return to_xy(frame, s, d, v, self.step_s)


WALL_NORMALS = np.array([[0.0, 1.0], [0.0, -1.0], [-1.0, 0.0]])  # inwards from the right, left bound, the end


def obstacle_distances(own, polys):
    """Footprint-to-footprint distances (M,B) of the egos' footprints own (M,4,2) to obstacle
    polygons (B,k,2) in the frame, and unit directions (M,B,2) from each obstacle's nearest point
    towards the ego (in contact: from the obstacle's centre to the ego's)."""
    m, b = len(own), len(polys)
    dist, p_ego, p_obs = convex_distance(np.repeat(own, b, axis=0), np.tile(polys, (m, 1, 1)))
    away = p_ego - p_obs
    n = np.hypot(away[:, 0], away[:, 1])
    centre = np.repeat(own.mean(axis=1), b, axis=0) - np.tile(polys.mean(axis=1), (m, 1))
    away = np.where((n > 1e-6)[:, None], away, centre)
    away = away / np.maximum(np.hypot(away[:, 0], away[:, 1]), 1e-12)[:, None]
    return dist.reshape(m, b), away.reshape(m, b, 2)


def to_xy(frame, s, d, v, lead_s: float) -> np.ndarray:
    """(M,2) plane velocities of the commands v (M,2) = (s_dot, d_dot), with the commands'
    magnitudes, the frame taken one step of travel ahead (RoadView.to_xy_velocity, vectorised)."""
    speed = np.hypot(v[:, 0], v[:, 1])
    xy = frame.velocity_to_xy(s + np.maximum(v[:, 0], 0.0) * lead_s, d, v[:, 0], v[:, 1])
    n = np.hypot(xy[:, 0], xy[:, 1])
    return np.where((n > 1e-12)[:, None] & (speed > 1e-12)[:, None], xy / np.maximum(n, 1e-12)[:, None]
                    * speed[:, None], 0.0)
