"""The GA planner on a road: what it plans with in the ego's route frame (s along the route, d
across it, left positive; :mod:`sumo_avoid.road.frenet`). Pure numpy, no SUMO.

* **Walls**: the corridor of the lanes of the ego's direction its class may use ([d_lo(s), d_hi(s)],
  :func:`all_lanes_corridor`: every lane of each edge, bridged across junctions). Waypoints are kept ``margin`` inside it
  (:func:`corridor_clip`) and both bounds are also obstacle points every ``step_m``
  (:func:`wall_points`, moved outwards by the safety radius less that margin), so a segment
  between two waypoints keeps the margin from them too.
* **Moving vehicles** (:func:`meeting_points`): constant-velocity prediction along the road. With
  the ego planned at speed v, a vehicle at (s_j, d_j) moving at s_dot_j is within the longitudinal
  gap G = (L_j + L_ego)/2 + gap_m + headway_s |s_dot_j - v| (a faster car coming up behind needs
  room to brake for the ego) of the ego while |(s_j - s_ego) + (s_dot_j - v) t| < G; the
  stretch of road the ego covers during that time, s_ego + v t, is marked at the vehicle's d (its
  two sides and its centre line). A slower car ahead thus blocks its lane where the ego would catch
  up with it, a faster car behind the stretch where it would come alongside, a car keeping pace
  the whole horizon in its lane; a car that pulls away, or that the ego stays ahead of, marks
  nothing. A vehicle behind the ego in the ego's own lane is left out (it follows the ego).
* **Standing objects** (:func:`whole_lanes`): a static point blocks the whole width of its lane,
  or, within its measurement's uncertainty of a lane line, that line; its body lies along the lane
  beyond it.
* **Goal of a plan** (:func:`pick_lane`): the look-ahead point ``horizon`` ahead on the lane centre
  nearest the ego's own offset whose point keeps ``free_m`` from every obstacle point.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.road.route import LanePiece, lane_bounds

#: Waypoints are kept this much further inside the lanes than the lane bounds' points require: a
#: segment between two waypoints at the margin passes closer to the bound's points where the
#: corridor kinks (lane pieces joining), and would make no path usable.
CLIP_SLACK_M = 0.2


def in_frame(xy, pos, frame, s0: float, s_end: float, reach_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(points (M, 2) (s, d), their indices into ``xy`` (M,)): the points ``xy`` (K, 2) within
    ``reach_m`` of ``pos`` in the route frame ``frame`` (projected near s0), those with s in
    (s0 - 10 m, s_end + 10 m)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    idx = np.flatnonzero(np.hypot(*(xy - np.asarray(pos, float)).T) < reach_m)
    if len(idx) == 0:
        return np.zeros((0, 2)), idx
    s, d = frame.to_frenet(xy[idx], np.full(len(idx), s0), reach_m)
    keep = (s > s0 - 10.0) & (s < s_end + 10.0)
    return np.column_stack([s, d])[keep], idx[keep]


def lane_centres(pieces: tuple[LanePiece, ...], s: float, usable_only: bool = False) -> np.ndarray:
    """(K,) d of the centres of the lanes of the edge at arc length ``s`` (linear over its piece), m;
    with ``usable_only`` those the ego's class may use (:meth:`LanePiece.usable`)."""
    starts = np.array([p.s_start_m for p in pieces])
    p = pieces[int(np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(pieces) - 1))]
    f = 0.0 if p.s_end_m <= p.s_start_m else float(np.clip((s - p.s_start_m) / (p.s_end_m - p.s_start_m), 0.0, 1.0))
    c = (1.0 - f) * np.asarray(p.offsets_start_m, float) + f * np.asarray(p.offsets_end_m, float)
    return c[p.usable()] if usable_only else c


def all_lanes_corridor(pieces: tuple[LanePiece, ...]):
    """A function s (N,) -> (d_lo (N,), d_hi (N,)): the bounds of all the lanes of each edge of the
    route its vehicle class may use (:meth:`LanePiece.usable`: not a sidewalk, bike or bus lane for a
    car; every such lane of the ego's direction, to its very end: no taper before a junction), bridged
    linearly across junctions (from the bounds where the edge before ends to where the next one
    starts). Exact where the lanes run on through a junction; at a turn an approximation (the
    planner's walls; :class:`~sumo_avoid.road.route_lanes.RouteLanes` has the lane-keeping corridor)."""
    pts = []
    for piece in pieces:
        if piece.edge.startswith(":"):
            continue  # inside a junction: the line from the last bound to the next
        w, ok = np.asarray(piece.widths_m, float), piece.usable()
        for s, off in ((piece.s_start_m, piece.offsets_start_m), (piece.s_end_m, piece.offsets_end_m)):
            pts.append((s, *lane_bounds(off, w, ok)))
    s = np.maximum.accumulate(np.array([q[0] for q in pts]) + 1e-6 * np.arange(len(pts)))
    lo, hi = np.array([q[1] for q in pts]), np.array([q[2] for q in pts])

    def corridor(x):
        x = np.atleast_1d(np.asarray(x, float))
        return np.interp(x, s, lo), np.interp(x, s, hi)
    return corridor


def whole_lanes(points, ranges, pieces: tuple[LanePiece, ...], s_ego: float, tol_m: float, tol_per_m: float,
                shadow_depth_m: float = 0.0, shadow_step_m: float = 2.0) -> np.ndarray:
    """Static points (s, d) (K, 2), measured at ``ranges`` (K,) m, as lane blockers. A point is
    uncertain across the line of sight by tol = tol_m + tol_per_m x the range it was measured at
    (the radar's azimuth steps: 1 deg is 1.2 m at 70 m). One that lies clearly inside a lane
    (farther than tol from its lines) becomes three points, the right bound, the centre and the
    left bound of that lane (a standing object in a lane blocks the lane: the radar reports only an
    object's nearest point, and a path that keeps the safety radius from that point alone runs into
    the rest of the object). One within tol of a lane line is put on that line: an object's edge
    there, on one side or the other (at long range a point can read well into either neighbouring
    lane). Each resulting point also marks the object's body beyond it, along the lane away from
    the ego (``shadow_depth_m`` deep, a point every ``shadow_step_m``): a standing object on a road
    lies along its lane, not along the line of sight (across a bend, a shadow along the line of
    sight would fall in the next lane). Lane centres and widths
    from the edge at the point's s. Returns (M, 2)."""
    pts = np.asarray(points, float).reshape(-1, 2)
    rng = np.broadcast_to(np.asarray(ranges, float), (len(pts),))
    out = [np.zeros((0, 2))]
    for (s, d), r in zip(pts, rng):
        c = lane_centres(pieces, s)
        i = int(np.argmin(np.abs(c - d)))
        half = 0.5 * _width_at(pieces, s, i)
        if half - abs(d - c[i]) <= tol_m + tol_per_m * float(r):
            out.append(np.array([[s, c[i] + np.copysign(half, d - c[i])]]))
        else:
            out.append(np.array([[s, c[i] - half], [s, c[i]], [s, c[i] + half]]))
    lanes = np.concatenate(out)
    if shadow_depth_m <= 0.0 or shadow_step_m <= 0.0 or len(lanes) == 0:
        return lanes
    steps = np.arange(0, int(shadow_depth_m / shadow_step_m) + 1) * shadow_step_m
    away = np.where(lanes[:, 0] >= s_ego, 1.0, -1.0)
    body = lanes[:, None, :] + np.stack([away[:, None] * steps[None], np.zeros((len(lanes), len(steps)))], -1)
    return body.reshape(-1, 2)


def _width_at(pieces, s: float, lane: int) -> float:
    starts = np.array([p.s_start_m for p in pieces])
    p = pieces[int(np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(pieces) - 1))]
    return float(p.widths_m[min(lane, len(p.widths_m) - 1)])


def corridor_clip(corridor, margin_m: float, s_lo: float, s_hi: float):
    """A function (N, n, 2) -> (N, n, 2) for the GA's ``bounds``: inner waypoints sorted by s (a path
    does not go back along the road), s clipped to [s_lo, s_hi], d kept ``margin_m`` inside the
    corridor at their s (its middle where it is narrower than 2 margin_m)."""
    def clip(pop):
        out = np.array(pop, float)
        inner = out[:, 1:-1]
        inner = np.take_along_axis(inner, np.argsort(inner[..., 0], axis=1, kind="stable")[..., None], axis=1)
        s = np.clip(inner[..., 0], s_lo, s_hi)
        lo, hi = corridor(s.ravel())
        lo, hi = lo.reshape(s.shape) + margin_m, hi.reshape(s.shape) - margin_m
        mid = 0.5 * (lo + hi)
        inner[..., 0] = s
        inner[..., 1] = np.where(lo <= hi, np.clip(inner[..., 1], lo, hi), mid)
        out[:, 1:-1] = inner
        return out
    return clip


def wall_points(corridor, s_lo: float, s_hi: float, step_m: float, out_m: float = 0.0) -> np.ndarray:
    """(2K, 2) points (s, d) every ``step_m`` along both bounds of the corridor over [s_lo, s_hi],
    each moved ``out_m`` outwards (a path keeping the safety radius r from them keeps r - out_m
    from the bound)."""
    s = np.arange(s_lo, s_hi + 0.5 * step_m, step_m)
    lo, hi = corridor(s)
    return np.concatenate([np.column_stack([s, lo - out_m]), np.column_stack([s, hi + out_m])])


def meeting_points(o_pos, o_vel, o_len, o_wid, s_ego: float, d_ego: float, v_plan: float, ego_len: float,
                   gap_m: float, s_end: float, step_m: float, own_lane_half_m: float,
                   headway_s: float = 0.0) -> np.ndarray:
    """(K, 2) points (s, d) marking where the ego, planned at ``v_plan`` m/s, would be within the
    longitudinal gap of moving vehicle j (centres ``o_pos`` (O, 2) (s, d), velocities ``o_vel``
    (O, 2) (s_dot, d_dot), lengths and widths (O,)), up to ``s_end`` (module docstring)."""
    out = [np.zeros((0, 2))]
    v = max(float(v_plan), 0.1)
    t_end = max(s_end - s_ego, 0.0) / v
    for (sj, dj), (vj, _), lj, wj in zip(np.asarray(o_pos, float).reshape(-1, 2), np.asarray(o_vel, float).reshape(-1, 2),
                                         o_len, o_wid):
        if sj < s_ego and abs(dj - d_ego) < own_lane_half_m:
            continue  # behind in the ego's own lane: it follows the ego
        g0, rel = sj - s_ego, vj - v
        G = 0.5 * (lj + ego_len) + gap_m + headway_s * abs(rel)
        if abs(rel) < 1e-9:
            t1, t2 = (0.0, t_end) if abs(g0) < G else (1.0, 0.0)
        else:
            ta, tb = sorted(((-G - g0) / rel, (G - g0) / rel))
            t1, t2 = max(ta, 0.0), min(tb, t_end)
        if t2 < t1:
            continue
        s = np.arange(s_ego + v * t1, s_ego + v * t2 + 0.5 * step_m, step_m)
        for dd in (-0.5 * wj, 0.0, 0.5 * wj):
            out.append(np.column_stack([s, np.full(len(s), dj + dd)]))
    return np.concatenate(out)


def pick_lane(centres, d_ego: float, s_goal: float, points, free_m: float) -> float:
    """d of the lane centre (of ``centres``) for the plan's end point at ``s_goal``: of those whose
    point (s_goal, d) keeps ``free_m`` from every obstacle point (s, d) (P, 2), the nearest to
    ``d_ego`` (a tie: the right one, lower d); if none does, the one with the most clearance."""
    c = np.sort(np.asarray(centres, float))
    pts = np.asarray(points, float).reshape(-1, 2)
    if len(pts) == 0:
        clear = np.full(len(c), np.inf)
    else:
        clear = np.hypot(s_goal - pts[None, :, 0], c[:, None] - pts[None, :, 1]).min(axis=1)
    ok = clear >= free_m
    if not ok.any():
        return float(c[int(np.argmax(clear))])
    return float(c[ok][int(np.argmin(np.abs(c[ok] - d_ego)))])


def follow_speed(o_pos, o_len, o_wid, s_ego: float, d_lanes, ego_len: float, ego_wid: float,
                 margin_m: float, decel_mps2: float, standstill_m: float) -> float:
    """The speed from which the ego stops behind a vehicle ahead in its strip, m/s (inf: none):
    vehicles (s, d) ahead whose footprint overlaps [d - ego_wid/2 - margin, d + ego_wid/2 + margin]
    for any d of ``d_lanes`` (the ego's offset and its path's offset at the vehicle, (O,) each or
    scalars), v <= sqrt(2 b (gap - standstill)). The leader's own speed does not count: it hides
    what is in the lane ahead of it (the radar sees its back), and when it swerves round a standing
    obstacle the ego must be able to stop before that obstacle where the leader was."""
    pos = np.asarray(o_pos, float).reshape(-1, 2)
    if len(pos) == 0:
        return np.inf
    gap = pos[:, 0] - s_ego - 0.5 * (np.asarray(o_len) + ego_len)
    reach = 0.5 * (np.asarray(o_wid) + ego_wid) + margin_m
    near = np.zeros(len(pos), bool)
    for d in np.atleast_1d(d_lanes):
        near |= np.abs(pos[:, 1] - d) < reach
    ahead = near & (pos[:, 0] > s_ego)
    if not ahead.any():
        return np.inf
    free = np.maximum(gap[ahead] - standstill_m, 0.0)
    return float(np.sqrt(2.0 * decel_mps2 * free).min())
