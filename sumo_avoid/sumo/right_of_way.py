"""Right of way at junctions, read once from the net's junction logic (``<request response=...>``
through :mod:`sumolib`): for a link of an ego's route, the links that have priority over it and
where their vehicles come from.

A foe link F has priority over the ego's link E when the junction's response for E has F's bit set
(``sumolib.net.node.Node.forbids(F, E)``): the major road over a minor one, the ring over a
roundabout entry, right before left at an equal junction, the oncoming straight over a permissive
left turn. The conflict point is where the two links' internal-lane chains first cross (along F);
links that merge without crossing conflict at the end of F's chain (the merge).

For F, :attr:`~sumo_avoid.core.types.FoeLink.approach` lists every lane a vehicle can be on while
it is heading for the conflict point, each with the distance from that lane's start to the point
along the way (SUMO lane lengths, so that SUMO's lane position gives the distance directly):
F's internal lanes up to the conflict, F's incoming lane, and the lanes upstream of it (internal
lanes of the junctions before included, so a roundabout's ring is followed back through its
junctions) up to ``horizon_m`` before F's stop line.
"""
from __future__ import annotations

from shapely.geometry import LineString, Point

from sumo_avoid.core.types import FoeLink


class RightOfWay:
    """The junction logic of one sumolib net (read with ``withInternal=True``, foes on)."""

    def __init__(self, net, horizon_m: float = 120.0):
        self.net = net
        self.horizon_m = horizon_m

    def via_chain(self, conn) -> list:
        """The internal lanes (sumolib lanes) a connection runs over, in order (one or several)."""
        out, via, target = [], conn.getViaLaneID(), conn.getToLane().getID()
        while via and len(out) < 32:
            lane = self.net.getLane(via)
            out.append(lane)
            outs = lane.getOutgoing()
            nxt = next((c for c in outs if c.getToLane().getID() == target), outs[0] if outs else None)
            via = "" if nxt is None else nxt.getViaLaneID()
            if nxt is not None and not via and nxt.getToLane().getID().startswith(":"):
                via = nxt.getToLane().getID()
        return out

    def foes(self, conn) -> tuple[FoeLink, ...]:
        """The links with priority over ``conn`` (a sumolib connection between normal lanes)."""
        node = conn.getFrom().getToNode()
        if not getattr(node, "_prohibits", None):
            return ()
        mine = self.via_chain(conn)
        out = []
        for other in node.getConnections():
            if other is conn or other.getFromLane().getID().startswith(":") or not node.forbids(other, conn):
                continue
            chain = self.via_chain(other)
            approach: dict[str, float] = {}
            conflict = _conflict_offset(chain, mine)
            acc = 0.0
            for ln in chain:  # internal lanes up to the conflict point
                if acc > conflict:
                    break
                approach[ln.getID()] = conflict - acc
                acc += ln.getLength()
            self._upstream(other.getFromLane(), conflict + other.getFromLane().getLength(), approach)
            tls = other.getTLSID() or ""
            out.append(FoeLink(tls, int(other.getTLLinkIndex()) if tls else -1, other.getState() or "",
                               other.getDirection() or "", tuple(sorted(approach.items())), float(conflict)))
        return tuple(out)

    def _upstream(self, lane, offset_m: float, out: dict) -> None:
        """Add ``lane`` (conflict ``offset_m`` from its start) and the lanes feeding it, back to
        ``horizon_m`` before the conflict (each lane once, at its smallest offset)."""
        todo = [(lane, offset_m)]
        while todo:
            ln, off = todo.pop()
            lid = ln.getID()
            if lid in out and out[lid] <= off:
                continue
            out[lid] = off
            if off - ln.getLength() > self.horizon_m:
                continue
            for conn in ln.getIncomingConnections():
                src = conn.getFromLane()
                if src.getID().startswith(":"):  # internal lane feeding this one directly
                    todo.append((src, off + src.getLength()))
                    continue
                acc = off
                for v in reversed(self.via_chain(conn)):
                    acc += v.getLength()
                    if out.get(v.getID(), float("inf")) > acc:
                        out[v.getID()] = acc
                todo.append((src, acc + src.getLength()))


def _chain_line(lanes) -> LineString | None:
    pts = [p for ln in lanes for p in ln.getShape()]
    return LineString(pts) if len(pts) >= 2 else None


def _conflict_offset(foe_lanes, ego_lanes) -> float:
    """Distance along the foe's internal lanes (SUMO lengths) from their start to the first point
    where they cross the ego's (their whole length if they only merge)."""
    total = float(sum(ln.getLength() for ln in foe_lanes))
    f, e = _chain_line(foe_lanes), _chain_line(ego_lanes)
    if f is None or e is None or f.length <= 0:
        return total
    hit = f.intersection(e)
    if hit.is_empty:
        return total
    pts = [Point(c) for g in getattr(hit, "geoms", [hit]) for c in g.coords]
    return total * min(1.0, min(f.project(p) for p in pts) / f.length)  # geometric -> SUMO length
