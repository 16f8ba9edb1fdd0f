"""Road geometry read once from a SUMO ``.net.xml`` with :mod:`sumolib` (no libsumo needed).

Conventions follow :mod:`sumo_avoid.core.snapshot`: metres, SUMO network x/y (east/north).

* ``area`` is the drivable surface: the union of every lane polygon (lane centre shape
  buffered by width/2 with flat caps, internal lanes included) and every junction polygon.
* ``boundary_segments`` are the edges of that surface (exterior and hole rings).
* ``solid_lines`` are markings that must not be crossed. Choice: for each normal edge, the
  *left border of its leftmost lane* (its centre shape offset by +width/2 to the left). In a
  two-way street this is the centre line between the opposite directions; on a one-way road
  it coincides with the left road edge (harmless duplicate of a boundary segment). Borders
  between same-direction lanes are *not* solid (lane changes are allowed).

The :class:`Road` object is immutable; :meth:`Road.from_net_file` caches the parse per file.
"""
from __future__ import annotations

import functools
import os
from typing import NamedTuple

import numpy as np
import shapely
import sumolib
from shapely.geometry import LineString, MultiPolygon, Polygon

from sumo_avoid.road.polyline import (
    _cumlen,
    polyline_length,
    polyline_point_at,
    polyline_project,
)
from sumo_avoid.road.elements import read_elements
from sumo_avoid.road.lane_index import LaneIndex
from sumo_avoid.road.route import LanePiece, OncomingLane, RouteLink
from sumo_avoid.road.right_of_way import RightOfWay, link_state


class RoutePlan(NamedTuple):
    """What :meth:`Road.route` gives for an ego's route."""

    path: np.ndarray  # (P, 2) reference polyline, m
    links: tuple[RouteLink, ...]  # junction links passed, in route order
    speed_limits: np.ndarray  # (K, 2) [s where a lane piece starts, its speed limit], m, m/s
    lanes: tuple[LanePiece, ...]  # lane pieces of the path


def _lane_centres(lanes) -> tuple[tuple[float, ...], np.ndarray]:
    """Widths and lateral centre positions (from the right edge, m) of an edge's lanes by index
    (lane 0 is the rightmost)."""
    w = np.array([float(ln.getWidth()) for ln in sorted(lanes, key=lambda ln: ln.getIndex())])
    return tuple(w.tolist()), np.cumsum(w) - 0.5 * w


def _keep_mask(points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """False for a point within ``tol`` of the one before it (consecutive duplicates)."""
    keep = np.ones(len(points), bool)
    if len(points) >= 2:
        keep[1:] = np.hypot(*np.diff(points, axis=0).T) > tol
    return keep


def _dedupe(points: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Drop consecutive duplicate points."""
    return points[_keep_mask(points, tol)] if len(points) >= 2 else points


def _offset_left(shape: np.ndarray, dist: float) -> np.ndarray:
    """Polyline offset by ``dist`` to the left of its direction of travel (mitred joins)."""
    if len(shape) < 2:
        return shape.copy()
    # per-segment left normals, averaged (mitre) at inner vertices
    d = np.diff(shape, axis=0)
    n = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.hypot(d[:, 0], d[:, 1])[:, None]
    normals = np.empty_like(shape)
    normals[0], normals[-1] = n[0], n[-1]
    if len(shape) > 2:
        m = n[:-1] + n[1:]
        m /= np.maximum(np.hypot(m[:, 0], m[:, 1]), 1e-9)[:, None]
        cos_half = np.einsum("ij,ij->i", m, n[1:])
        normals[1:-1] = m / np.maximum(cos_half, 0.2)[:, None]
    return shape + dist * normals


def _rings(geom) -> list[np.ndarray]:
    polys = geom.geoms if isinstance(geom, MultiPolygon) else [geom]
    out = []
    for poly in polys:
        if poly.is_empty:
            continue
        out.append(np.asarray(poly.exterior.coords))
        out.extend(np.asarray(r.coords) for r in poly.interiors)
    return out


def _segments(polylines: list[np.ndarray]) -> np.ndarray:
    segs = [np.stack([p[:-1], p[1:]], axis=1) for p in polylines if len(p) >= 2]
    if not segs:
        return np.zeros((0, 2, 2))
    s = np.concatenate(segs)
    return s[np.hypot(*(s[:, 1] - s[:, 0]).T) > 1e-9]


def _ro(a) -> np.ndarray:
    arr = np.array(a, dtype=float, copy=True)
    arr.flags.writeable = False
    return arr


# --------------------------------------------------------------------------- Road
class Road:
    """Immutable road geometry of one SUMO network. Build with :meth:`from_net_file`."""

    def __init__(self, net, source: str = ""):
        s = object.__setattr__
        s(self, "source", source)
        s(self, "_net", net)
        s(self, "elements", read_elements(net))  # lanes with permissions, junctions, crossings, walking areas
        lanes = [ln for e in net.getEdges(withInternal=True) for ln in e.getLanes()]
        polys = []
        for ln in lanes:
            shape = np.asarray(ln.getShape(), float)
            if len(shape) >= 2:
                polys.append(LineString(shape).buffer(ln.getWidth() / 2.0, cap_style="flat", join_style="mitre",
                                                      mitre_limit=3.0))
        for node in net.getNodes():
            shp = node.getShape()
            if shp is not None and len(shp) >= 3:
                jp = shapely.make_valid(Polygon(shp))
                if jp.area > 1e-6:
                    polys.append(jp)
        area = shapely.unary_union(polys)
        area = area.buffer(0.01, join_style="mitre").buffer(-0.01, join_style="mitre")
        area = shapely.simplify(area, 1e-3)
        if not isinstance(area, (Polygon, MultiPolygon)):  # GeometryCollection after ops
            area = shapely.unary_union([g for g in getattr(area, "geoms", [area]) if g.area > 0])
        shapely.prepare(area)
        s(self, "area", area)
        s(self, "bounds", tuple(float(v) for v in area.bounds))

        # markings of normal edges
        solid, dashed, outer = [], [], []
        for e in net.getEdges(withInternal=False):
            if e.getFunction() == "internal":
                continue
            ls = sorted(e.getLanes(), key=lambda ln: ln.getIndex())
            for i, ln in enumerate(ls):
                shape = np.asarray(ln.getShape(), float)
                left = _offset_left(shape, ln.getWidth() / 2.0)
                (solid if i == len(ls) - 1 else dashed).append(_ro(left))
                if i == 0:
                    outer.append(_ro(_offset_left(shape, -ln.getWidth() / 2.0)))
        s(self, "_solid_polylines", tuple(solid))
        s(self, "_dashed_polylines", tuple(dashed))
        s(self, "_outer_polylines", tuple(outer))
        s(self, "boundary_segments", _ro(_segments(_rings(area))))
        s(self, "solid_lines", _ro(_segments(solid)))

        allseg = np.concatenate([self.boundary_segments, self.solid_lines])
        s(self, "_all_segments", _ro(allseg))
        s(self, "_all_is_solid", _ro(np.r_[np.zeros(len(self.boundary_segments)), np.ones(len(self.solid_lines))])
          .astype(bool))
        s(self, "_seg_lo", _ro(allseg.min(axis=1)) if len(allseg) else np.zeros((0, 2)))
        s(self, "_seg_hi", _ro(allseg.max(axis=1)) if len(allseg) else np.zeros((0, 2)))

    def __setattr__(self, name, value):
        raise AttributeError("Road is immutable")

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_net_file(cls, path) -> Road:
        """Parse ``path`` once (cached per absolute path and modification time)."""
        p = os.path.abspath(os.fspath(path))
        return _load_cached(p, os.stat(p).st_mtime_ns)

    # ------------------------------------------------------------------ area queries
    def outside_distance(self, points) -> np.ndarray:
        """(M,2) points -> (M,) distance to the drivable area (0 inside or on the edge)."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        out = np.zeros(len(pts))
        if len(pts) == 0:
            return out
        inside = shapely.contains_xy(self.area, pts[:, 0], pts[:, 1])
        if not inside.all():
            idx = np.flatnonzero(~inside)
            out[idx] = shapely.distance(self.area, shapely.points(pts[idx]))
        return out

    def footprint_outside_distance(self, corners) -> np.ndarray:
        """(N,4,2) footprint corners -> (N,) max corner distance outside the area."""
        c = np.asarray(corners, dtype=float).reshape(-1, 4, 2)
        return self.outside_distance(c.reshape(-1, 2)).reshape(-1, 4).max(axis=1, initial=0.0)

    def segments_near(self, point, radius_m: float, *, with_kind: bool = False):
        """Boundary segments and solid lines within ``radius_m`` of ``point``.

        Returns (k,2,2) segments (boundary segments first, then solid lines); with
        ``with_kind=True`` returns ``(segments, is_solid)`` where is_solid is a (k,) bool array.
        """
        q = np.asarray(point, dtype=float).reshape(2)
        r = float(radius_m)
        m = np.all((self._seg_lo - r <= q) & (self._seg_hi + r >= q), axis=1)
        idx = np.flatnonzero(m)
        if len(idx):
            a, b = self._all_segments[idx, 0], self._all_segments[idx, 1]
            d = b - a
            l2 = np.einsum("ij,ij->i", d, d)
            t = np.clip(np.einsum("ij,ij->i", q - a, d) / np.maximum(l2, 1e-12), 0.0, 1.0)
            f = a + t[:, None] * d - q
            idx = idx[np.einsum("ij,ij->i", f, f) <= r * r]
        segs = self._all_segments[idx].copy()
        return (segs, self._all_is_solid[idx].copy()) if with_kind else segs

    # ------------------------------------------------------------------ lanes and routes
    def _lane(self, edge_id: str, lane_index: int):
        return self._net.getEdge(edge_id).getLanes()[lane_index]

    def lane_shape(self, edge_id: str, lane_index: int) -> np.ndarray:
        """(P,2) centre shape of a lane."""
        return np.asarray(self._lane(edge_id, lane_index).getShape(), float)

    def lane_centre_at(self, edge_id: str, lane_index: int, pos_m: float) -> np.ndarray:
        """Lane centre point at SUMO lane position ``pos_m`` (as reported for the front bumper)."""
        ln = self._lane(edge_id, lane_index)
        shape = np.asarray(ln.getShape(), float)
        geo = polyline_length(shape)
        factor = geo / ln.getLength() if ln.getLength() > 0 else 1.0  # SUMO lengthGeometryFactor
        return polyline_point_at(shape, pos_m * factor)

    def route_path(self, edge_ids, depart_lane: int | None = None, arrival_lane: int | None = None) -> np.ndarray:
        """Reference polyline (P,2) along the route (:meth:`route`)."""
        return self.route(edge_ids, depart_lane, arrival_lane).path

    def route(self, edge_ids, depart_lane: int | None = None, arrival_lane: int | None = None) -> RoutePlan:
        """Reference polyline (P,2) along consecutive normal edges, joined by internal lanes, and
        the junction links it passes (:class:`RouteLink`: stop line arc length, signal, right of way),
        the speed limits along it ((K, 2): arc length where a lane piece starts, its speed, m/s) and
        its lane pieces (:class:`LanePiece`: edge, lane, where the edge's other lanes lie across it).

        On every edge one lane is used that has a connection to the next edge (the one
        nearest to the lane we entered on, or to ``depart_lane`` on the first edge). If the
        entry lane differs from that lane (e.g. requested depart/arrival lane has no such
        connection), the path blends from one lane to the other over the first
        min(half the edge, 60 m).
        """
        edges = [self._net.getEdge(e) for e in edge_ids]
        if not edges:
            raise ValueError("empty route")
        pieces: list[np.ndarray] = []
        link_at: list[tuple[object, int]] = []  # (connection, points before its stop line)
        limit_at: list[tuple[float, int]] = []  # (speed limit, points before its lane piece)
        piece_at: list[tuple] = []  # (edge, lane, offsets at start, offsets at end, widths, points before it)
        n_points = 0
        entry = depart_lane
        for k, e in enumerate(edges):
            lanes = e.getLanes()
            if k + 1 < len(edges):
                conns = e.getConnections(edges[k + 1])
                if not conns:
                    raise ValueError(f"no connection {e.getID()} -> {edges[k + 1].getID()}")
                ref = entry if entry is not None else 0
                want_to = arrival_lane if (k + 2 == len(edges) and arrival_lane is not None) else None
                conn = min(conns, key=lambda c: (abs(c.getFromLane().getIndex() - ref),
                                                 0 if want_to is None else abs(c.getToLane().getIndex() - want_to),
                                                 c.getFromLane().getIndex()))
                exit_idx = conn.getFromLane().getIndex()
            else:
                conn = None
                exit_idx = arrival_lane if arrival_lane is not None else (entry if entry is not None else 0)
            exit_idx = int(np.clip(exit_idx, 0, len(lanes) - 1))
            entry_idx = exit_idx if entry is None else int(np.clip(entry, 0, len(lanes) - 1))
            exit_shape = np.asarray(lanes[exit_idx].getShape(), float)
            limit_at.append((float(lanes[exit_idx].getSpeed()), n_points))
            widths, centres = _lane_centres(lanes)
            exit_off = tuple((centres - centres[exit_idx]).tolist())
            if entry_idx != exit_idx:
                entry_shape = np.asarray(lanes[entry_idx].getShape(), float)
                L = polyline_length(exit_shape)
                s0 = min(0.5 * L, 60.0)
                cum = _cumlen(exit_shape)
                pieces += [entry_shape[:1], polyline_point_at(exit_shape, s0)[None], exit_shape[cum > s0]]
                piece_at.append((e.getID(), exit_idx, tuple((centres - centres[entry_idx]).tolist()), exit_off, widths, n_points))
                piece_at.append((e.getID(), exit_idx, exit_off, exit_off, widths, n_points + 2))
            else:
                pieces.append(exit_shape)
                piece_at.append((e.getID(), exit_idx, exit_off, exit_off, widths, n_points))
            n_points = sum(len(piece) for piece in pieces)
            if conn is not None:
                link_at.append((conn, n_points))
                for lane, shape, speed in self._via_lanes(conn):
                    limit_at.append((speed, n_points))
                    piece_at.append((lane.getEdge().getID(), lane.getIndex(), (0.0,), (0.0,),
                                     (float(lane.getWidth()),), n_points))
                    pieces.append(shape)
                    n_points += len(shape)
                entry = conn.getToLane().getIndex()
        points = np.concatenate(pieces)
        keep = _keep_mask(points, tol=1e-3)
        path = points[keep]
        cum = _cumlen(path)
        kept_before = np.concatenate([[0], np.cumsum(keep)])  # kept points among the first n

        def s_at(n: int) -> float:  # arc length where the points after the first n begin
            return float(cum[kept_before[n] - 1]) if kept_before[n] else 0.0

        links = tuple(self._link(conn, s_at(n)) for conn, n in link_at)
        limits = np.array([(s_at(n), v) for v, n in limit_at], float).reshape(-1, 2)
        starts = [s_at(n) for *_, n in piece_at]
        ends = starts[1:] + [float(cum[-1])]
        lane_pieces = tuple(LanePiece(a, max(a, b), edge, lane, o0, o1, w)
                            for (edge, lane, o0, o1, w, _), a, b in zip(piece_at, starts, ends))
        return RoutePlan(path, links, limits, lane_pieces)

    def _link(self, conn, s_stop_m: float) -> RouteLink:
        tls = conn.getTLSID() or ""
        return RouteLink(float(s_stop_m), conn.getFrom().getToNode().getID(), tls,
                         int(conn.getTLLinkIndex()) if tls else -1, link_state(conn), conn.getDirection() or "",
                         self.right_of_way.foes(conn), self._oncoming(conn.getTo(), conn),
                         tuple(o.lane for o in self._oncoming(conn.getFrom())))

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

    # ------------------------------------------------------------------ plotting support
    def lane_lines(self, kind: str | None = None) -> list[np.ndarray]:
        """Lane markings of normal edges as (P,2) polylines.

        kind="dashed": borders between same-direction lanes; "median": left border of each
        edge's leftmost lane (= ``solid_lines``); "edge": right border of each rightmost lane;
        "solid": median + edge; None: all of them.
        """
        kinds = {
            "dashed": self._dashed_polylines,
            "median": self._solid_polylines,
            "edge": self._outer_polylines,
            "solid": self._solid_polylines + self._outer_polylines,
            None: self._dashed_polylines + self._solid_polylines + self._outer_polylines,
        }
        if kind not in kinds:
            raise ValueError(f"unknown kind {kind!r}")
        return list(kinds[kind])

    polyline_length = staticmethod(polyline_length)
    polyline_point_at = staticmethod(polyline_point_at)
    polyline_project = staticmethod(polyline_project)

    def __repr__(self) -> str:
        return f"Road({os.path.basename(self.source)!r}, area={self.area.area:.0f} m2, bounds={self.bounds})"

    @functools.cached_property
    def right_of_way(self) -> RightOfWay:
        """The junction logic (which links yield to which), built on first use."""
        return RightOfWay(self._net)

    # ------------------------------------------------------------------ lane lookup (metrics)
    @functools.cached_property
    def lanes(self) -> LaneIndex:
        """The normal lanes and junctions for point queries (:class:`LaneIndex`), built on first use."""
        return LaneIndex(self._net)


@functools.lru_cache(maxsize=16)
def _load_cached(path: str, mtime_ns: int) -> Road:
    net = sumolib.net.readNet(path, withInternal=True)
    return Road(net, source=path)
