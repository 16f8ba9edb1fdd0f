"""An ego's route on the net (read once with :mod:`sumolib`): the reference path along its edges
joined by internal lanes, the junction links it passes (stop line, signal, right of way, the lanes
running the other way, the pedestrian crossings), the speed limits and the lane pieces
(:mod:`sumo_avoid.road.route`). Built by :meth:`sumo_avoid.road.network.Road.route`."""
from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from sumo_avoid.road.crossings import crossing_links
from sumo_avoid.road.polyline import _cumlen, path_frames, polyline_length, polyline_point_at, cut_spurs, ease_jogs
from sumo_avoid.road.right_of_way import RightOfWay, link_state
from sumo_avoid.road.route import LanePiece, OncomingLane, RouteLink

CROSSING_REACH_M = 10.0  # a link's crossings are looked for this far before and after its internal lanes, m
WAIT_CLEAR_M = 1.8  # a turn waiting inside a junction keeps its front corners this far from a crossing foe's
#: path (its centre line: half a car's width and 0.9 m to spare for the ego's heading, which leads the path), m
WAIT_HALF_WIDTH_M = 1.0  # ... taken for a car this half wide, m
HOLD_CLEAR_M = 1.2  # a car waiting for a junction keeps its front corners this far from other links' paths into it
#: (their centre lines: a turning car's half width and 0.3 m to spare), m
HOLD_BACK_M = 8.0  # ... moving back from the stop line at most this far, m
KERB_REACH_M = 1.0  # how far beyond an internal lane's borders a walkway is looked for (kerb_room), m


class RoutePlan(NamedTuple):
    """What :meth:`Road.route` gives for an ego's route."""

    path: np.ndarray  # (P, 2) reference polyline, m
    links: tuple[RouteLink, ...]  # junction links passed, in route order
    speed_limits: np.ndarray  # (K, 3) [s where a lane piece starts, its speed limit, 1 if a junction's internal lane], m, m/s
    lanes: tuple[LanePiece, ...]  # lane pieces of the path



def _lane_centres(lanes, lefthand: bool = False) -> tuple[tuple[float, ...], np.ndarray]:
    """Widths and lateral centre positions (d, positive left, from lane 0's outer edge, m) of an edge's lanes
    by index: lane 0 is the rightmost, or in left-hand traffic the leftmost (the indices grow to the right)."""
    w = np.array([float(ln.getWidth()) for ln in sorted(lanes, key=lambda ln: ln.getIndex())])
    c = np.cumsum(w) - 0.5 * w
    return tuple(w.tolist()), -c if lefthand else c


def _opposite(e, vclass: str | None) -> tuple[float, str]:
    """(width, id) of the lane beside ``e``'s leftmost one on the edge running the other way between the same
    junctions, if ``vclass`` may use it ((0, "") otherwise, or when there is no such edge)."""
    a, b = e.getFromNode(), e.getToNode()
    for r in b.getOutgoing():
        if r.getToNode() is a and r.getID() != e.getID() and r.getFunction() == "":
            lane = max(r.getLanes(), key=lambda ln: ln.getIndex())
            return (float(lane.getWidth()), lane.getID()) if vclass is None or lane.allows(vclass) else (0.0, "")
    return 0.0, ""


def _first_allowed(lanes, vclass: str | None) -> int:
    """The lowest lane index ``vclass`` may use (0 without a class, or when it may use none)."""
    ok = [ln.getIndex() for ln in lanes if vclass is None or ln.allows(vclass)]
    return min(ok) if ok else 0


def kerb_room(plan: RoutePlan, on_walkway, reach_m: float = KERB_REACH_M, step_m: float = 0.5) -> tuple[LanePiece, ...]:
    """The plan's lane pieces, each internal one with :attr:`LanePiece.kerb_room_m`: how far beyond its
    lane's right and left borders the first point ``on_walkway`` ((M,2) -> (M,) bool) lies, sampled every
    ``step_m`` along the piece and every 5 cm out to ``reach_m`` (the room a junction's corridor may widen
    into: a car's corner does not cross the kerb into people walking on a corner)."""
    path, out = plan.path, []
    cum = _cumlen(path)
    ts = np.arange(0.0, reach_m + 1e-9, 0.05)
    for p in plan.lanes:
        if not p.edge.startswith(":") or p.s_end_m - p.s_start_m <= 0.0:
            out.append(p)
            continue
        s = np.linspace(p.s_start_m, p.s_end_m, max(int((p.s_end_m - p.s_start_m) / step_m) + 2, 2))
        pts, _, left = path_frames(path, cum, s)
        half = 0.5 * p.widths_m[p.lane if len(p.widths_m) > p.lane else 0]  # an internal piece lists its own lane only
        room = []
        for side in (-1.0, 1.0):  # right, left
            probe = pts[:, None, :] + side * (half + ts)[None, :, None] * left[:, None, :]
            hit = np.asarray(on_walkway(probe.reshape(-1, 2)), bool).reshape(len(s), len(ts))
            first = np.where(hit.any(axis=1), ts[np.argmax(hit, axis=1)], np.inf)
            room.append(float(first.min()))
        out.append(replace(p, kerb_room_m=(room[0], room[1])))
    return tuple(out)


def _usable(conns, vclass: str | None) -> list:
    """The connections ``vclass`` may use (both lanes allow it), or all of them when it may use none (a class no
    connection admits keeps SUMO's route as it is)."""
    mine = [c for c in conns if vclass is None or (c.getFromLane().allows(vclass) and c.getToLane().allows(vclass))]
    return mine or list(conns)


def _blend_m(e) -> float:
    """How long the path's change from one lane to another on edge ``e`` is: min(half the edge, 60 m)."""
    return min(0.5 * float(e.getLength()), 60.0)


def _with_change(m: int, e, onward: tuple[int, float]) -> tuple[int, float]:
    """(lane changes, steepness) of changing ``m`` lanes on edge ``e`` and then going on at cost ``onward``."""
    return m + onward[0], round(m / _blend_m(e) + onward[1], 9)


def lane_costs(edges, arrival_lane: int | None, vclass: str | None) -> list[dict[int, tuple[int, float]]]:
    """Per edge k, for each lane index the path may enter ``edges[k]`` by: (the lane changes the rest of the route
    needs from there, their steepness: the sum over them of lanes changed / the length of the edge's blend,
    1/m), worked backwards from the arrival lane (every lane ``vclass`` may use when none is given). Planning
    with them changes lanes where the route needs as few changes as any, and of those where they are least
    steep: on a long edge, not on the short piece a net splits off before a junction (with the lane changed
    only on the edge before the one that needs it, unseen Chiang Mai car118 crossed a 15 m edge at 21 degrees
    into a queue, stood on the diagonal and was clipped twice in the lane it left)."""
    last = edges[-1]
    lanes = sorted(last.getLanes(), key=lambda ln: ln.getIndex())
    goals = ([int(arrival_lane)] if arrival_lane is not None else
             [ln.getIndex() for ln in lanes if vclass is None or ln.allows(vclass)] or [ln.getIndex() for ln in lanes])
    n = {ln.getIndex(): min(abs(ln.getIndex() - g) for g in goals) for ln in lanes}
    costs = [{i: (k, k / _blend_m(last)) for i, k in n.items()}]
    for k in range(len(edges) - 2, -1, -1):
        e, onward = edges[k], costs[0]
        here: dict[int, tuple[int, float]] = {}
        for c in _usable(e.getConnections(edges[k + 1]), vclass):
            to = onward.get(c.getToLane().getIndex())
            if to is None:
                continue
            j = c.getFromLane().getIndex()
            for ln in e.getLanes():
                m = abs(ln.getIndex() - j)
                cand = _with_change(m, e, to)
                here[ln.getIndex()] = min(here.get(ln.getIndex(), cand), cand)
        costs.insert(0, here)
    return costs


def _turning(conn, via_lanes) -> float:
    """Total absolute change of heading, rad, along a connection: from the end of its lane on the
    incoming edge through its internal lanes ``via_lanes`` to the start of its lane on the outgoing edge."""
    pts = [np.asarray(conn.getFromLane().getShape(), float)[-2:]]
    pts += [np.asarray(v.getShape(), float) for v in via_lanes]
    pts.append(np.asarray(conn.getToLane().getShape(), float)[:2])
    p = _dedupe(np.concatenate(pts))
    if len(p) < 3:
        return 0.0
    h = np.arctan2(*np.diff(p, axis=0).T[::-1])
    return float(np.abs((np.diff(h) + np.pi) % (2 * np.pi) - np.pi).sum())


def _keep_mask(points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """False for a point within ``tol`` of the one before it (consecutive duplicates)."""
    keep = np.ones(len(points), bool)
    if len(points) >= 2:
        keep[1:] = np.hypot(*np.diff(points, axis=0).T) > tol
    return keep


def _dedupe(points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Drop consecutive duplicate points."""
    return points[_keep_mask(points, tol)] if len(points) >= 2 else points



class RoutePlanner:
    """Routes on one sumolib net (read with internal lanes and pedestrian connections)."""

    def __init__(self, net, right_of_way: RightOfWay, lefthand: bool = False):
        self._net = net
        self.right_of_way = right_of_way
        self.lefthand = lefthand  # left-hand traffic (Road.lefthand)

    def route(self, edge_ids, depart_lane: int | None = None, arrival_lane: int | None = None,
              vclass: str | None = None) -> RoutePlan:
        """Reference polyline (P,2) along consecutive normal edges, joined by internal lanes, and
        the junction links it passes (:class:`RouteLink`: stop line arc length, signal, right of way),
        the speed limits along it ((K, 3): arc length where a lane piece starts, its speed, m/s, and 1 where
        the piece is a junction's internal lane, whose speed is netconvert's turning speed, no legal limit) and
        its lane pieces (:class:`LanePiece`: edge, lane, where the edge's other lanes lie across it).

        On every edge one lane is used that has a connection to the next edge (the one
        nearest to the lane we entered on, or to ``depart_lane`` on the first edge). If the
        entry lane differs from that lane (e.g. requested depart/arrival lane has no such
        connection), the path blends from one lane to the other over the first
        min(half the edge, 60 m). With ``vclass`` each lane piece says which lanes of its edge that
        class may use (:attr:`LanePiece.allowed`), and a lane the path is free to choose (the last
        edge's without an arrival lane) is the lowest-index one the class may use.
        """
        edges = [self._net.getEdge(e) for e in edge_ids]
        if not edges:
            raise ValueError("empty route")
        pieces: list[np.ndarray] = []
        link_at: list[tuple[object, int]] = []  # (connection, points before its stop line)
        limit_at: list[tuple[float, int, float]] = []  # (speed limit, points before its lane piece, 1: a turning speed)
        piece_at: list[tuple] = []  # (edge, lane, offsets at start, offsets at end, widths, allowed, (opposite width, lane), points before it)
        entry = depart_lane
        costs = lane_costs(edges, arrival_lane, vclass)
        for k, e in enumerate(edges):
            nxt = edges[k + 1] if k + 1 < len(edges) else None
            conn, exit_idx = self._exit(e, nxt, entry, costs[k + 1] if nxt is not None else {}, arrival_lane, vclass)
            self._lay_edge(e, entry, exit_idx, vclass, pieces, piece_at, limit_at, self.lefthand)
            if conn is not None:
                n_points = sum(len(piece) for piece in pieces)
                link_at.append((conn, n_points))
                for lane, shape, speed in self._via_lanes(conn):
                    limit_at.append((speed, n_points, 1.0))
                    piece_at.append((lane.getEdge().getID(), lane.getIndex(), (0.0,), (0.0,),
                                     (float(lane.getWidth()),), (), (0.0, ""), n_points))
                    pieces.append(shape)
                    n_points += len(shape)
                entry = conn.getToLane().getIndex()
        return self._plan(pieces, link_at, limit_at, piece_at)

    def _exit(self, e, nxt, entry, onward: dict, arrival_lane, vclass):
        """(the connection to edge ``nxt`` the path takes, None on the last edge; the lane index it
        leaves ``e`` by): of the connections ``vclass`` may use, the one after which the route needs the fewest
        lane changes in all (here and ``onward``, :func:`lane_costs` of ``nxt``), of those the least steep ones,
        of those the one from the lane nearest the entry lane (a change is left to a later edge where that is as
        good), then the smoothest (the least turning, :func:`_turning`: where one lane fans out into several,
        the lane that runs on rather than one reached by a jog)."""
        lanes = e.getLanes()
        if nxt is None:
            exit_idx = arrival_lane if arrival_lane is not None else (entry if entry is not None else
                                                                      _first_allowed(lanes, vclass))
            return None, int(np.clip(exit_idx, 0, len(lanes) - 1))
        conns = _usable(e.getConnections(nxt), vclass)
        if not conns:
            raise ValueError(f"no connection {e.getID()} -> {nxt.getID()}")
        ref = entry if entry is not None else 0
        far = (10**6, 0.0)  # into a lane from which the route cannot go on

        def key(c):
            m, to = abs(c.getFromLane().getIndex() - ref), onward.get(c.getToLane().getIndex(), far)
            return (*_with_change(m, e, to), m,
                    round(_turning(c, self.right_of_way.via_chain(c)), 3), c.getFromLane().getIndex())
        conn = min(conns, key=key)
        return conn, int(np.clip(conn.getFromLane().getIndex(), 0, len(lanes) - 1))

    @staticmethod
    def _lay_edge(e, entry, exit_idx: int, vclass, pieces: list, piece_at: list, limit_at: list,
                  lefthand: bool = False) -> None:
        """Append edge ``e``'s points (its exit lane's shape, blended in from the entry lane over
        min(half the edge, 60 m) when they differ), its lane pieces and its speed limit."""
        lanes = e.getLanes()
        n_points = sum(len(piece) for piece in pieces)
        allowed = () if vclass is None else tuple(bool(ln.allows(vclass)) for ln in
                                                  sorted(lanes, key=lambda ln: ln.getIndex()))
        entry_idx = exit_idx if entry is None else int(np.clip(entry, 0, len(lanes) - 1))
        exit_shape = np.asarray(lanes[exit_idx].getShape(), float)
        limit_at.append((float(lanes[exit_idx].getSpeed()), n_points, 0.0))
        widths, centres = _lane_centres(lanes, lefthand)
        exit_off = tuple((centres - centres[exit_idx]).tolist())
        opp = (*_opposite(e, vclass), lefthand)  # (in left-hand traffic the oncoming lane lies on the right)
        if entry_idx == exit_idx:
            pieces.append(exit_shape)
            piece_at.append((e.getID(), exit_idx, exit_off, exit_off, widths, allowed, opp, n_points))
            return
        entry_shape = np.asarray(lanes[entry_idx].getShape(), float)
        s0 = min(0.5 * polyline_length(exit_shape), 60.0)
        cum = _cumlen(exit_shape)
        pieces += [entry_shape[:1], polyline_point_at(exit_shape, s0)[None], exit_shape[cum > s0]]
        piece_at.append((e.getID(), exit_idx, tuple((centres - centres[entry_idx]).tolist()), exit_off, widths,
                         allowed, opp, n_points))
        piece_at.append((e.getID(), exit_idx, exit_off, exit_off, widths, allowed, opp, n_points + 2))

    def _plan(self, pieces, link_at, limit_at, piece_at) -> RoutePlan:
        """The path from the laid points (consecutive duplicates dropped) and, at the arc lengths where
        their points begin, the links, speed limits and lane pieces."""
        points = np.concatenate(pieces)
        keep = _keep_mask(points, tol=1e-3)
        kept = np.flatnonzero(keep)
        points = points.copy()
        points[kept], spur_free = cut_spurs(points[kept])  # out-and-back spurs of lanes laid apart
        keep[kept[~spur_free]] = False
        path, where = ease_jogs(points[keep])  # sideways steps of the lanes (a car cannot step aside)
        cum = _cumlen(path)
        kept_before = np.concatenate([[0], np.cumsum(keep)])  # kept points among the first n

        def s_at(n: int) -> float:  # arc length where the points after the first n begin
            return float(cum[where[kept_before[n] - 1]]) if kept_before[n] else 0.0

        links = tuple(self._link(conn, s_at(n), path, cum) for conn, n in link_at)
        limits = np.array([(s_at(n), v, turn) for v, n, turn in limit_at], float).reshape(-1, 3)
        starts = [s_at(n) for *_, n in piece_at]
        ends = starts[1:] + [float(cum[-1])]
        lane_pieces = tuple(LanePiece(a, max(a, b), edge, lane, o0, o1, w, ok, *opp)
                            for (edge, lane, o0, o1, w, ok, opp, _), a, b in zip(piece_at, starts, ends))
        return RoutePlan(path, links, limits, lane_pieces)

    def _link(self, conn, s_stop_m: float, path: np.ndarray, cum: np.ndarray) -> RouteLink:
        tls = conn.getTLSID() or ""
        chain = self.right_of_way.via_chain(conn)
        through = sum(v.getLength() for v in chain)
        # SUMO's drivers wait inside the junction where the link's internal lane is split (an internal
        # junction); the ego waits there too, its front corners WAIT_CLEAR_M from the crossing foes' paths
        wait = (self.right_of_way.wait_s(conn, path, cum, s_stop_m, WAIT_CLEAR_M, WAIT_HALF_WIDTH_M)
                if len(chain) > 1 else float("nan"))
        return RouteLink(float(s_stop_m), conn.getFrom().getToNode().getID(), tls,
                         int(conn.getTLLinkIndex()) if tls else -1, link_state(conn), conn.getDirection() or "",
                         self.right_of_way.foes(conn), self._oncoming(conn.getTo(), conn),
                         tuple(o.lane for o in self._oncoming(conn.getFrom())),
                         crossing_links(self._net, conn, path, cum, s_stop_m - CROSSING_REACH_M,
                                        s_stop_m + through + CROSSING_REACH_M), float(wait),
                         self.right_of_way.inside(conn),
                         self.right_of_way.hold_s(conn, path, cum, s_stop_m, HOLD_CLEAR_M, WAIT_HALF_WIDTH_M, HOLD_BACK_M),
                         self.right_of_way.crossers(conn))

    def _oncoming(self, edge, conn=None) -> tuple[OncomingLane, ...]:
        """The lane bordering ``edge`` on every edge that runs the other way between the same two
        junctions (its highest-index lane, next to the opposite direction in SUMO); ``gives_way``:
        one of its links gives way to ``conn``."""
        a, b = edge.getFromNode().getID(), edge.getToNode().getID()
        mine = np.asarray(edge.getLanes()[-1].getShape(), float)
        tangent = mine[1] - mine[0]
        out = []
        for e in edge.getToNode().getOutgoing():
            if e.getToNode().getID() == a and e.getFromNode().getID() == b and e.getID() != edge.getID():
                lane = e.getLanes()[-1]
                rel = np.asarray(lane.getShape(), float)[-1] - mine[0]  # its end, beside the start of ``edge``
                side = 1 if tangent[0] * rel[1] - tangent[1] * rel[0] > 0 else -1
                inside = tuple(dict.fromkeys(v.getID() for c in lane.getOutgoing() for v in self.right_of_way.via_chain(c)))
                waits = conn is not None and self.right_of_way.gives_way_to(lane, conn)
                out.append(OncomingLane(lane.getID(), float(lane.getLength()), side, inside, waits))
        return tuple(out)

    def _via_lanes(self, conn) -> list[tuple]:
        """(lane, shape, speed limit) of the chain of internal lanes of a connection (possibly split in several)."""
        return [(lane, np.asarray(lane.getShape(), float), float(lane.getSpeed()))
                for lane in self.right_of_way.via_chain(conn)]
