"""Where SUMO should think an ego is (SPEC §5, "SUMO's true view of the ego").

The plug-in moves each ego with ``moveToXY`` to the exact pose the actuator computed. How SUMO
maps that pose onto its network decides which of SUMO's vehicles see the ego (as a leader, a foe
at a junction, a collision partner):

* **On its route** (the centre within the lanes of the ego's direction along its route,
  :meth:`~sumo_avoid.road.route_lanes.RouteLanes.lane_at`; junctions widened): ``keepRoute=1`` with the
  edge and lane as hints. SUMO maps the ego onto the closest lane of the edges ahead on its route
  (internal lanes included) and keeps the route, so the ego stopped at a roundabout entry is on
  the entry lane, not on the ring.
* **Off its route** (an oncoming lane while overtaking, off the road): ``keepRoute=2`` without
  hints, exact position anywhere; SUMO replaces the route by the edge it maps to.
* **Back on its route** after that: ``keepRoute=2`` with the edge and lane as hints (SUMO prefers
  the hinted lane), then the rest of the original route from that edge is set again
  (``setRoute``); inside a junction this waits for the next normal edge.

The ego's s along its path is followed step by step (RouteFrame, window around the last s), so a
route that passes near itself is not confused.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.road.frenet import RouteFrame
from sumo_avoid.road.route_lanes import RouteLanes
from sumo_avoid.core.types import EgoTask

ON_ROUTE, OFF_ROUTE = 1, 2  # moveToXY keepRoute values


@dataclass
class _Track:
    frame: RouteFrame
    lanes: RouteLanes
    edges: tuple[str, ...]  # the route's normal edges, in order
    s_m: float | None = None
    off: bool = False  # SUMO has the ego on a route of its own making


class RoutePlacement:
    """Per ego: the lane hint and keepRoute mode for its next pose (pure; no SUMO calls)."""

    def __init__(self):
        self._tracks: dict[str, _Track] = {}

    def follow(self, task: EgoTask, route_edges) -> None:
        if task.lanes and len(task.path) >= 2:
            self._tracks[task.vid] = _Track(RouteFrame.from_polyline(task.path), RouteLanes(task.lanes),
                                            tuple(route_edges))

    def lost(self, vid: str) -> None:
        """SUMO did not take the route back (the ego was mapped elsewhere): try again next step."""
        if vid in self._tracks:
            self._tracks[vid].off = True

    def forget(self, vid: str) -> None:
        self._tracks.pop(vid, None)

    def place(self, vid: str, centre: np.ndarray) -> tuple[str, int, int, tuple[str, ...]]:
        """(edge hint, lane hint, keepRoute, route to set afterwards or ()) for ego ``vid`` at
        ``centre`` (2,). Egos not followed (an arena's flock) go anywhere: ("", -1, 2, ())."""
        t = self._tracks.get(vid)
        if t is None:
            return "", -1, OFF_ROUTE, ()
        s, d = t.frame.point_to_frenet(float(centre[0]), float(centre[1]), t.s_m)
        t.s_m = float(s)
        hit = t.lanes.lane_at(t.s_m, float(d))
        if hit is None:
            t.off = True
            return "", -1, OFF_ROUTE, ()
        edge, lane = hit
        if not t.off:
            return edge, lane, ON_ROUTE, ()
        if edge.startswith(":") or edge not in t.edges:
            return edge, lane, OFF_ROUTE, ()
        t.off = False
        return edge, lane, OFF_ROUTE, t.edges[t.edges.index(edge):]
