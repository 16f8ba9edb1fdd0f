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
import gzip
import os
import re

import numpy as np
import shapely
import sumolib
from shapely.geometry import LineString, MultiPolygon, Polygon

from sumo_avoid.road.elements import read_elements
from sumo_avoid.road.grade import apart_parts
from sumo_avoid.road.lane_index import LaneIndex
from sumo_avoid.road.overlaps import oncoming_narrowing
from sumo_avoid.road.polyline import polyline_length, polyline_point_at, polyline_project
from sumo_avoid.road.right_of_way import RightOfWay
from sumo_avoid.road.route_plan import RoutePlan, RoutePlanner, kerb_room
from sumo_avoid.road.uturns import without_uturns


WALKWAY_TOL_M = 0.3  # a point this close to a sidewalk or walking area is on it (Road.on_walkway), m
KERB_CAP_M = 1.0  # people waiting at a crossing stand up to this far beyond its end (Road.at_kerb), m


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


def _surface(lanes, nodes):
    """The union of the lanes' polygons (centre shape buffered by width/2, flat caps) and the junction shapes."""
    polys = []
    for ln in lanes:
        shape = np.asarray(ln.getShape(), float)
        if len(shape) >= 2:
            polys.append(LineString(shape).buffer(ln.getWidth() / 2.0, cap_style="flat", join_style="mitre",
                                                  mitre_limit=3.0))
    for node in nodes:
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
    return area


# --------------------------------------------------------------------------- Road
class Road:
    """Immutable road geometry of one SUMO network. Build with :meth:`from_net_file`."""

    def __init__(self, net, source: str = "", lefthand: bool = False):
        s = object.__setattr__
        s(self, "source", source)
        s(self, "_net", net)
        s(self, "lefthand", bool(lefthand))  # left-hand traffic: lane 0 is the left kerb lane (net attribute lefthand)
        side = -1.0 if lefthand else 1.0  # which way (left of travel = +1) the lane indices grow
        s(self, "elements", read_elements(net))  # lanes with permissions, junctions, crossings, walking areas
        lanes = [ln for e in net.getEdges(withInternal=True) for ln in e.getLanes()]
        area = _surface(lanes, net.getNodes())
        s(self, "_lanes_all", tuple(lanes))
        s(self, "_areas", {})  # vehicle class -> its drivable area (area_for), built on first use
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
                left = _offset_left(shape, side * ln.getWidth() / 2.0)  # its border towards the next index
                (solid if i == len(ls) - 1 else dashed).append(_ro(left))
                if i == 0:
                    outer.append(_ro(_offset_left(shape, -side * ln.getWidth() / 2.0)))
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
    def outside_distance(self, points, vclass: str | None = None) -> np.ndarray:
        """(M,2) points -> (M,) distance to the drivable area (0 inside or on the edge); with ``vclass``,
        to that class's area (:meth:`area_for`)."""
        area = self.area_for(vclass)
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        out = np.zeros(len(pts))
        if len(pts) == 0:
            return out
        inside = shapely.contains_xy(area, pts[:, 0], pts[:, 1])
        if not inside.all():
            idx = np.flatnonzero(~inside)
            out[idx] = shapely.distance(area, shapely.points(pts[idx]))
        return out

    def footprint_outside_distance(self, corners, vclass: str | None = None) -> np.ndarray:
        """(N,4,2) footprint corners -> (N,) max corner distance outside the area (``vclass``'s)."""
        c = np.asarray(corners, dtype=float).reshape(-1, 4, 2)
        return self.outside_distance(c.reshape(-1, 2), vclass).reshape(-1, 4).max(axis=1, initial=0.0)

    def area_for(self, vclass: str | None):
        """The drivable area of a vehicle class: the lanes (internal ones included) the net opens to it
        and the junction shapes; :attr:`area` (every lane) when it may use every lane or for None."""
        if vclass is None:
            return self.area
        if vclass not in self._areas:
            mine = [ln for ln in self._lanes_all if ln.allows(vclass)]
            self._areas[vclass] = self.area if len(mine) == len(self._lanes_all) else _surface(mine, self._net.getNodes())
        return self._areas[vclass]

    def on_walkway(self, points) -> np.ndarray:
        """(M,2) points -> (M,) bool: on a sidewalk or walking area (:attr:`RoadElements.walkways`: a
        lane only people walk on, off the carriageway), or within :data:`WALKWAY_TOL_M` of one (a radar
        return lies on a person's near side; SUMO stands the people waiting for a crossing on its end,
        where a rounded corner leaves a few centimetres outside the walking area)."""
        return self._inside("walkway", self._walkway_polygons, points)

    def at_kerb(self, points) -> np.ndarray:
        """(M,2) points -> (M,) bool: :meth:`on_walkway`, or where SUMO stands the people waiting at a
        crossing's end: across the crossing's whole width, up to :data:`KERB_CAP_M` beyond its end (its
        striping model spreads them over the crossing's width, which can reach past the walking area
        onto the lane beside it -- Bologna's corner 1c: 1 m). A radar return there is a person at the
        kerb, not on the carriageway (the crossing rule, not the margin, decides when it may step on)."""
        return self._inside("kerb", lambda: self._walkway_polygons() + self._crossing_ends(), points)

    def _walkway_polygons(self) -> list:
        polys = []
        for lane_id in self.elements.walkways:
            ln = self.elements.lanes[lane_id]
            shape = np.asarray(ln.shape, float)[:, :2]
            if ln.function == "walkingarea" and len(shape) >= 3:
                polys.append(Polygon(shape).buffer(0))
            elif len(shape) >= 2:
                polys.append(LineString(shape).buffer(0.5 * ln.width_m, cap_style="flat"))
        return polys

    def _crossing_ends(self) -> list:
        """A rectangle at each end of each crossing: its width across, from its end to KERB_CAP_M beyond."""
        out = []
        for c in self.elements.crossings.values():
            shape = np.asarray(c.shape, float)[:, :2]
            if len(shape) < 2:
                continue
            for end, prev in ((shape[-1], shape[-2]), (shape[0], shape[1])):
                axis = end - prev
                n = float(np.hypot(*axis))
                if n < 1e-9:
                    continue
                axis /= n
                out.append(LineString([end, end + KERB_CAP_M * axis]).buffer(0.5 * c.width_m, cap_style="flat"))
        return out

    def _inside(self, key: str, polygons, points) -> np.ndarray:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if key not in self._areas:
            polys = polygons()
            area = shapely.union_all(polys).buffer(WALKWAY_TOL_M) if polys else Polygon()
            shapely.prepare(area)
            self._areas[key] = area
        if len(pts) == 0:
            return np.zeros(0, bool)
        return np.asarray(shapely.contains_xy(self._areas[key], pts[:, 0], pts[:, 1]), bool)

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

    def route(self, edge_ids, depart_lane: int | None = None, arrival_lane: int | None = None,
              vclass: str | None = None) -> RoutePlan:
        """The route along consecutive normal edges (:meth:`RoutePlanner.route`)."""
        plan = self.planner.route(edge_ids, depart_lane, arrival_lane, vclass)
        if self.elements.walkways:
            plan = plan._replace(lanes=kerb_room(plan, self.on_walkway))
        return plan._replace(lanes=oncoming_narrowing(plan, self.lanes, self._net.getLane, self.apart, vclass))

    def without_uturns(self, edge_ids, vclass: str | None):
        """The fastest route round the U-turns of route ``edge_ids``, or None (:mod:`sumo_avoid.road.uturns`)."""
        return without_uturns(self._net, edge_ids, vclass)

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
    def planner(self) -> RoutePlanner:
        """Route paths, links and lane pieces on this net, built on first use."""
        return RoutePlanner(self._net, self.right_of_way, self.lefthand)

    @functools.cached_property
    def right_of_way(self) -> RightOfWay:
        """The junction logic (which links yield to which), built on first use."""
        return RightOfWay(self._net)

    @functools.cached_property
    def apart(self):
        """Edge -> the edges whose lanes cross its own without a junction: two levels (:mod:`.grade`), built on first use."""
        return apart_parts(self._net) if self._net is not None else {}

    # ------------------------------------------------------------------ lane lookup (metrics)
    @functools.cached_property
    def lanes(self) -> LaneIndex:
        """The normal lanes and junctions for point queries (:class:`LaneIndex`), built on first use."""
        return LaneIndex(self._net)

    def lane_heading(self, points) -> np.ndarray:
        """(M,2) points -> (M,) rad: the direction of the normal lane each point lies in (of several, the one
        whose centre line is nearest), NaN where none (inside a junction, where internal lanes of every
        direction overlap; on a crossing or walking area; off the lanes). A radar return placed on the map
        this way tells which way the road user it belongs to is bound to move
        (:mod:`sumo_avoid.sensing.perception`), as an ADAS fuses its radar with its map."""
        _, direction = self.lanes.lane_at(points)
        return np.arctan2(direction[:, 1], direction[:, 0]) if len(direction) else np.zeros(0)


@functools.lru_cache(maxsize=16)
def _load_cached(path: str, mtime_ns: int) -> Road:
    net = sumolib.net.readNet(path, withInternal=True, withPedestrianConnections=True, withPrograms=True)
    return Road(net, source=path, lefthand=_lefthand(path))


def _lefthand(path: str) -> bool:
    """The net file's ``lefthand`` attribute (SUMO's left-hand traffic; sumolib does not read it): from its
    ``<net ...>`` element, which follows the header comment within the first few kilobytes."""
    with (gzip.open(path, "rt", errors="replace") if path.endswith(".gz") else
          open(path, errors="replace")) as f:
        head = f.read(1 << 20)
    m = re.search(r"<net\s[^>]*>", head)
    return bool(m and re.search(r'\slefthand="(true|1)"', m.group(0)))
