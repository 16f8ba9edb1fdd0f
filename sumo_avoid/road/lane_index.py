"""Which lane a point is in, and that lane's direction there: a shapely STRtree over the polygons of
a network's normal lanes (centre shape buffered by width/2, flat caps, as in
:class:`~sumo_avoid.road.network.Road`), with their centre lines; junction shapes apart.

Used after a run (the ``wrong_way_m`` metric), built once per network on first use
(:attr:`sumo_avoid.road.network.Road.lanes`). Read with :mod:`sumolib`, no libsumo.
"""
from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon

STEP_M = 0.5  # the lane direction is the centre line's chord from s - STEP_M to s + STEP_M, m


class LaneIndex:
    """Normal lanes (not internal lanes, crossings or walking areas) and junction polygons of a net."""

    def __init__(self, net):
        ids, lines, polys = [], [], []
        for e in net.getEdges(withInternal=False):
            if e.getFunction() not in ("", "normal"):
                continue
            for ln in e.getLanes():
                shape = np.asarray(ln.getShape(), float)
                if len(shape) < 2:
                    continue
                line = LineString(shape)
                if line.length <= 1e-9:
                    continue
                ids.append(ln.getID())
                lines.append(line)
                polys.append(line.buffer(ln.getWidth() / 2.0, cap_style="flat", join_style="mitre", mitre_limit=3.0))
        junctions = []
        for node in net.getNodes():
            shp = node.getShape()
            if shp is not None and len(shp) >= 3:
                jp = shapely.make_valid(Polygon(shp))
                if jp.area > 1e-6:
                    junctions.append(jp)
        self.ids = tuple(ids)
        self._lines = np.array(lines, dtype=object)
        self._polys = np.array(polys, dtype=object)
        self._tree = shapely.STRtree(polys)
        self._junctions = shapely.unary_union(junctions) if junctions else shapely.Polygon()
        shapely.prepare(self._junctions)

    def in_junction(self, points) -> np.ndarray:
        """(M,2) points -> (M,) True inside (or on) a junction shape."""
        pts = np.asarray(points, float).reshape(-1, 2)
        return shapely.intersects_xy(self._junctions, pts[:, 0], pts[:, 1]) if len(pts) else np.zeros(0, bool)

    def lane_at(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(M,2) points -> (lane index into :attr:`ids`, -1 where none; (M,2) unit direction of that
        lane's centre line at the point's projection, NaN where none). Of several lane polygons
        holding a point (borders, bends), the lane whose centre line is nearest."""
        pts = np.asarray(points, float).reshape(-1, 2)
        lane = np.full(len(pts), -1, np.int64)
        direction = np.full((len(pts), 2), np.nan)
        if not len(pts) or not len(self._lines):
            return lane, direction
        geoms = shapely.points(pts)
        p, q = self._tree.query(geoms, predicate="intersects")
        if not len(p):
            return lane, direction
        d = shapely.distance(self._lines[q], geoms[p])
        o = np.lexsort((q, d, p))  # per point, nearest centre line first (ties: lower lane index)
        p, q = p[o], q[o]
        first = np.r_[True, p[1:] != p[:-1]]
        p, q = p[first], q[first]
        lane[p] = q
        direction[p] = self._directions(geoms, p, q)
        return lane, direction

    def holding(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(M,2) points -> every (point, lane) pair where lane :attr:`ids` [q] holds point [p]: (K,), (K,)."""
        pts = np.asarray(points, float).reshape(-1, 2)
        if not len(pts) or not len(self._lines):
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return self._tree.query(shapely.points(pts), predicate="intersects")

    def crossing(self, geoms) -> tuple[np.ndarray, np.ndarray]:
        """Shapely geometries (segments) -> every (geometry, lane) pair that intersects: (K,), (K,)."""
        return self._tree.query(geoms, predicate="intersects")

    def polygon(self, q):
        """The polygon of lane :attr:`ids` [q] (an array of them for an array of indices)."""
        return self._polys[q]

    def direction(self, q: int, point) -> np.ndarray:
        """(2,) unit direction of lane :attr:`ids` [q]'s centre line where ``point`` projects on it."""
        return self._directions(shapely.points(np.asarray(point, float).reshape(1, 2)), np.zeros(1, np.int64),
                                np.array([q]))[0]

    def _directions(self, geoms, p, q) -> np.ndarray:
        """(K,2) unit direction of lane q[k]'s centre line where point geoms[p[k]] projects on it."""
        lines = self._lines[q]
        s = shapely.line_locate_point(lines, geoms[p])
        length = shapely.length(lines)  # (a negative distance would count from the end)
        a = shapely.get_coordinates(shapely.line_interpolate_point(lines, np.clip(s - STEP_M, 0.0, length)))
        b = shapely.get_coordinates(shapely.line_interpolate_point(lines, np.clip(s + STEP_M, 0.0, length)))
        chord = b - a
        return chord / np.hypot(chord[:, 0], chord[:, 1])[:, None]

    def against(self, points, motion) -> np.ndarray:
        """(M,2) points and (M,2) directions (the ``wrong_way_m`` metric passes the car's heading)
        -> (M,) True where the point is in a normal lane, outside every junction, and the direction
        of *every* lane holding it is more than 90° from the given direction. (Where a net lays two
        roads over each other, a car in its own lane is also in the other road's: it is no ghost
        driver there.)"""
        pts = np.asarray(points, float).reshape(-1, 2)
        mv = np.asarray(motion, float).reshape(-1, 2)
        out = np.zeros(len(pts), bool)
        if not len(pts) or not len(self._lines):
            return out
        geoms = shapely.points(pts)
        p, q = self.holding(pts)
        if not len(p):
            return out
        agree = np.einsum("ij,ij->i", self._directions(geoms, p, q), mv[p]) >= 0.0
        held = np.zeros(len(pts), bool)
        held[p] = True
        fine = np.zeros(len(pts), bool)
        fine[p[agree]] = True
        return held & ~fine & ~self.in_junction(pts)
