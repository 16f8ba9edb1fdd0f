"""U-turns, and the way round them (SPEC §5: the route a car drives on SUMO roads).

SUMO's routers (duarouter, randomTrips.py) send a vehicle back the way it came wherever the net has a
turnaround (netconvert adds one at most junctions and at every dead end), and SUMO's driver turns on
the spot there. A car cannot. On a street with one lane each way, turning half a circle at its smallest
turning radius R (of its centre) sweeps a strip 2 R + W wide (W its width: 10.3 m for R = 4.25 m) where
there are 6-7 m; and where the room is there, a turnaround through a median opening, netconvert draws
the internal lane as a hook, and the plug-in's egos stood askew in it for good (unseen Peshawar, a dual
carriageway: 275 s, two cars clipped it). In OSM districts with randomTrips traffic a seventh to a third
of the car routes have one (Istanbul 48, Peshawar 108, Adlershof 127 of 334), and the egos stood before
them or left the road.

So the egos take the route a driver with a navigation system set to avoid U-turns takes:
:func:`without_uturns` gives, for a route with a turnaround (SUMO's link direction ``t``), the fastest
route from the same first edge to the same last edge (lengths over speed limits, as SUMO's routers
weigh edges) over links the vehicle class may use among those with the fewest: round the block. None when
the route has no turnaround, or none of them can be avoided (a dead end the car is in, or its destination
is: it keeps its route).
"""
from __future__ import annotations

import heapq


def _allowed(conn, vclass: str | None) -> bool:
    return vclass is None or (conn.getFromLane().allows(vclass) and conn.getToLane().allows(vclass))


def _links(a, b, vclass: str | None) -> list:
    """The links from edge ``a`` to edge ``b`` that ``vclass`` may use."""
    return [c for c in a.getOutgoing().get(b, ()) if _allowed(c, vclass)]


def _turnaround(links) -> bool:
    """Are these links from one edge to another a turnaround (all of them SUMO's direction ``t``)?"""
    return bool(links) and all(c.getDirection() == "t" for c in links)


def is_uturn(a, b, vclass: str | None) -> bool:
    """Is going from edge ``a`` to edge ``b`` a turnaround (its links, SUMO's direction ``t``)?"""
    return _turnaround(_links(a, b, vclass))


def uturns(net, edges, vclass: str | None) -> list[int]:
    """Positions k in ``edges`` where edges[k] -> edges[k + 1] is a turnaround."""
    e = [net.getEdge(x) for x in edges]
    return [k for k in range(len(e) - 1) if is_uturn(e[k], e[k + 1], vclass)]


def without_uturns(net, edges, vclass: str | None):
    """The fastest route from ``edges[0]`` to ``edges[-1]`` among those with the fewest turnarounds (tuple of
    edge ids), or None: ``edges`` has no turnaround, or none of its turnarounds can be avoided (module docstring)."""
    edges = list(edges)
    n = len(uturns(net, edges, vclass)) if len(edges) >= 2 else 0
    if n == 0:
        return None
    start, goal = net.getEdge(edges[0]).getID(), net.getEdge(edges[-1]).getID()
    if start == goal:
        return None
    best, back, heap = {start: (0, 0.0)}, {}, [(0, 0.0, start)]
    while heap:  # Dijkstra over edges by (turnarounds, travel time), ties by edge id: the same route every time
        k, t, eid = heapq.heappop(heap)
        if (k, t) > best[eid]:
            continue
        if eid == goal:
            if k >= n:
                return None
            path = [eid]
            while path[-1] in back:
                path.append(back[path[-1]])
            return tuple(reversed(path))
        a = net.getEdge(eid)
        for b in sorted(a.getOutgoing(), key=lambda x: x.getID()):
            links = _links(a, b, vclass)
            if b.getFunction() == "internal" or not links:
                continue
            cost = (k + _turnaround(links), t + b.getLength() / max(float(b.getSpeed()), 0.1))
            if cost < best.get(b.getID(), (float("inf"), 0.0)):
                best[b.getID()], back[b.getID()] = cost, eid
                heapq.heappush(heap, (*cost, b.getID()))
    return None
