"""Oncoming lanes that a net lays over the ego's own: where they narrow its corridor.

SUMO keeps the vehicles of two edges apart only through junctions: lanes of two edges that overlap in the
plane are no conflict to it, and its vehicles pass through each other there. Imported from OpenStreetMap, a
street mapped as two one-way ways drawn closer together than their lanes are wide becomes two edges whose
lanes overlap (unseen Cologne, Am Heumarkt: the left lanes of edges 1273089807 and 4583332#3 have centre lines
1.8-2.3 m apart at 3.2 m width, so 0.9-1.4 m of each lies in the other; two cars on their lane centres pass
0.5 m apart). The ego's corridor (:class:`~sumo_avoid.road.route_lanes.RouteLanes`) spans its own lanes, so it
may use the strip where oncoming cars really drive: a person walking in the ego's right lane pushed it 0.4 m
left and 0.33 rad askew, and an oncoming car at 14.2 m/s met its front corner head-on.

:func:`oncoming_narrowing` finds, along each normal lane piece of a route, every lane of another edge that
runs against the route (more than ``ANTIPARALLEL_DEG`` from it), is open to the ego's vehicle class (oncoming
traffic of its kind, not a tram track or a sidewalk), joins other junctions than the ego's edge (a net's own
opposite edge between the same two junctions that overlaps it is a lane both directions share on purpose, as
SUMO's bidirectional tram tracks in a street), lies on the ego's level (z within
:data:`~sumo_avoid.core.levels.LEVELS`, and not on an edge that crosses the ego's without a junction:
:mod:`~sumo_avoid.road.grade`) and reaches more than ``MIN_OVERLAP_M`` over the corridor's left or right
border; the corridor's border is moved back to that lane's border there (:attr:`LanePiece.narrowing_m`), but
never closer than ``MIN_HALF_ROOM_M`` to the centre of the lane the route follows: the ego keeps to its lane
rather than moving over into the next one, where SUMO's cars, which place it in its lane, pass it close (the
first version kept 2.4 m of the whole corridor: on Am Heumarkt the ego then drove 1 m right of its lane's
centre, and a car passing in the right lane clipped its rear). A two-way street's own opposite edge borders
the ego's lanes without overlapping them, so nothing changes there; lanes running the ego's way (a slip road
beside it) are other cars going its way, met as obstacles as before.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import shapely

from sumo_avoid.core.levels import LEVELS
from sumo_avoid.road.polyline import _cumlen, path_frames
from sumo_avoid.road.route import lane_bounds

#: Sampling step along a lane piece, m.
SAMPLE_M = 2.0
#: An oncoming lane reaching less than this over the corridor's border is a border drawn twice, m.
MIN_OVERLAP_M = 0.1
#: A lane counts as oncoming when its direction is more than this from the route's, degrees.
ANTIPARALLEL_DEG = 150.0
#: The narrowed corridor keeps at least this much room on each side of the centre of the lane the route follows
#: (half a car's 1.8 m and 0.3 m): the ego may always drive its lane's centre, as SUMO's cars do, m.
MIN_HALF_ROOM_M = 1.2


def _z_at(shape3d: np.ndarray, point: np.ndarray) -> float:
    """z of a lane's 3D centre shape where ``point`` (x, y) projects onto it."""
    line = shapely.LineString(shape3d[:, :2])
    s = line.project(shapely.Point(point))
    return float(np.interp(s, _cumlen(shape3d[:, :2]), shape3d[:, 2]))


def oncoming_narrowing(plan, index, lane_of, apart, vclass: str | None) -> tuple:
    """The plan's lane pieces, each normal one whose corridor an oncoming lane of another edge overlaps with
    :attr:`LanePiece.narrowing_m` (module doc). ``index``: the net's
    :class:`~sumo_avoid.road.lane_index.LaneIndex`; ``lane_of``: lane id -> its sumolib lane; ``apart``: edge
    id -> the edges crossing it without a junction; ``vclass``: the ego's vehicle class (None: passenger)."""
    path, out = plan.path, []
    cum = _cumlen(path)
    cos_max = np.cos(np.radians(ANTIPARALLEL_DEG))
    for p in plan.lanes:
        if p.edge.startswith(":") or p.s_end_m - p.s_start_m <= 0.0:
            out.append(p)
            continue
        n = max(int(np.ceil((p.s_end_m - p.s_start_m) / SAMPLE_M)) + 1, 2)
        s = np.linspace(p.s_start_m, p.s_end_m, n)
        pts, tan, left = path_frames(path, cum, s)
        f = (s - p.s_start_m) / (p.s_end_m - p.s_start_m)
        offs = (1.0 - f)[:, None] * np.asarray(p.offsets_start_m) + f[:, None] * np.asarray(p.offsets_end_m)
        ok = p.usable()
        bounds = np.array([lane_bounds(o, p.widths_m, ok) for o in offs])  # (n, 2) right, left
        cut = _cuts(p, pts, tan, left, bounds, index, lane_of, apart.get(p.edge, frozenset()), cos_max,
                    vclass or "passenger")
        if cut is None:
            out.append(p)
            continue
        centre = offs[:, p.lane]
        cut[:, 0] = np.minimum(cut[:, 0], np.maximum(centre - MIN_HALF_ROOM_M - bounds[:, 0], 0.0))
        cut[:, 1] = np.minimum(cut[:, 1], np.maximum(bounds[:, 1] - centre - MIN_HALF_ROOM_M, 0.0))
        if not cut.any():
            out.append(p)
            continue
        out.append(replace(p, narrowing_m=tuple((float(x), float(r), float(q)) for x, (r, q) in zip(s, cut))))
    return tuple(out)


def _cuts(p, pts, tan, left, bounds, index, lane_of, apart_edges, cos_max, vclass):
    """(n, 2) how far (right, left) oncoming lanes reach over the corridor's borders at each sample, or None."""
    segs = shapely.linestrings(np.stack([pts + bounds[:, :1] * left, pts + bounds[:, 1:] * left], axis=1))
    k, q = index.crossing(segs)
    if not len(k):
        return None
    cut = np.zeros((len(pts), 2))
    own = lane_of(f"{p.edge}_{p.lane}").getEdge()
    ends = {own.getFromNode().getID(), own.getToNode().getID()}
    own_shape = np.asarray(own.getLanes()[p.lane].getShape3D(), float)
    parts = shapely.intersection(segs[k], index.polygon(q))
    for i, j, inter in zip(k.tolist(), q.tolist(), parts):
        lane = lane_of(index.ids[j])
        edge = lane.getEdge()
        if (edge.getID() == p.edge or edge.getID() in apart_edges or not lane.allows(vclass)
                or {edge.getFromNode().getID(), edge.getToNode().getID()} == ends):
            continue
        part = shapely.get_coordinates(inter)
        if not len(part):
            continue
        d = (part - pts[i]) @ left[i]
        lo, hi = float(d.min()), float(d.max())
        mid = pts[i] + 0.5 * (lo + hi) * left[i]
        if float(index.direction(j, mid) @ tan[i]) > cos_max:
            continue
        z_other = _z_at(np.asarray(lane.getShape3D(), float), mid)
        if abs(z_other - _z_at(own_shape, mid)) > LEVELS.clearance_m:
            continue
        right, top = bounds[i]
        if hi >= top - 1e-6 and top - lo > MIN_OVERLAP_M and lo > right:
            cut[i, 1] = max(cut[i, 1], top - lo)
        elif lo <= right + 1e-6 and hi - right > MIN_OVERLAP_M and hi < top:
            cut[i, 0] = max(cut[i, 0], hi - right)
    return cut if cut.any() else None
