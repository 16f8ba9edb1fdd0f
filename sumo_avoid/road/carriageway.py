"""The carriageway along a route: the lanes of the route's direction as one corridor
d_lo(s) <= d <= d_hi(s) in the route's Frenet frame (d from the path's reference line, positive left).

Unlike :class:`~sumo_avoid.road.route_lanes.RouteLanes` (one car keeps its path's lane, so the other
lanes taper to it before a junction) the carriageway holds every lane that goes on: the walls of a
flock on a road (:mod:`sumo_avoid.control.flocking.road_flock`) and of a formation driving in its
leader's route frame (:mod:`sumo_avoid.control.formation.road_frame`).
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.road.route import LanePiece

#: Lanes that do not go on to the next edge of the route end in a taper over this length, m.
TAPER_M = 30.0
_EPS = 1e-6


def _edge_bounds(offsets, widths) -> np.ndarray:
    o, w = np.asarray(offsets, float), np.asarray(widths, float)
    return np.array([(o - 0.5 * w).min(), (o + 0.5 * w).max()])


class Carriageway:
    """The corridor along one route: d_lo(s) <= d <= d_hi(s), all lanes of the route's direction.

    Before a junction the bounds taper over the last min(``TAPER_M``, half the edge) from the edge's lanes
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
