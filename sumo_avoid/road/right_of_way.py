"""Right of way at junctions, read once from the net's junction logic (``<request response=...>``
through :mod:`sumolib`): for a link of an ego's route, the links that have priority over it and
where their vehicles come from.

A foe link F has priority over the ego's link E when the junction's response for E has F's bit set
(``sumolib.net.node.Node.forbids(F, E)``): the major road over a minor one, the ring over a
roundabout entry, right before left at an equal junction, the oncoming straight over a permissive
left turn. The conflict point is where the two links' internal-lane chains first cross (along F);
links that merge without crossing conflict at the end of F's chain (the merge).

For F, :attr:`~sumo_avoid.road.route.FoeLink.approach` lists every lane a vehicle can be on while
it is heading for the conflict point, each with the distance from that lane's start to the point
along the way (SUMO lane lengths, so that SUMO's lane position gives the distance directly):
F's internal lanes up to the conflict, F's incoming lane, and the lanes upstream of it (internal
lanes of the junctions before included, so a roundabout's ring is followed back through its
junctions) up to ``horizon_m`` before F's stop line.

An *unregulated* junction has no junction logic (SUMO's drivers go through without looking; SUMO
checks no collisions there): every link from another edge whose chain crosses the ego's, or ends
in the same lane, is a foe, and the ego's link counts as equal ('=', :func:`link_state`): it gives
way to all of them.
"""
from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import LineString, Point

from sumo_avoid.road.route import FoeLink

#: SUMO's junction type without right of way (netgenerate leaves e.g. a spider net's centre so).
UNREGULATED = "unregulated"


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
        """The links with priority over ``conn`` (a sumolib connection between normal lanes); at an
        unregulated junction every link from another edge that crosses or merges with it."""
        node = conn.getFrom().getToNode()
        mine = self.via_chain(conn)
        if node.getType() == UNREGULATED:
            line, target = _chain_line(mine), conn.getToLane().getID()
            others = ((o, self.via_chain(o)) for o in node.getConnections() if o.getFrom() is not conn.getFrom()
                      and not o.getFromLane().getID().startswith(":"))
            return tuple(self._foe(o, chain, mine) for o, chain in others
                         if o.getToLane().getID() == target or _crosses(_chain_line(chain), line))
        if not _has_logic(node):
            return ()
        return tuple(self._foe(other, self.via_chain(other), mine) for other in node.getConnections()
                     if other is not conn and not other.getFromLane().getID().startswith(":") and node.forbids(other, conn))

    def inside(self, conn) -> tuple[FoeLink, ...]:
        """The links *without* priority over ``conn`` (from another edge) whose internal lanes cross its
        own or end in its lane, each with only those internal lanes as its approach: a vehicle there is
        already in the junction. A car with priority still lets it clear the junction (SUMO's drivers
        treat it as a link leader; traffic law: who is in the junction clears it first), and SUMO's
        vehicles enter on such links whenever they see no SUMO-driven foe coming, which an ego moved by
        the plug-in standing at its line is not (Villeurbanne, unseen district: a cyclist waiting inside
        the junction to turn left set off as the ego's light turned green, and the two met at the exit)."""
        node = conn.getFrom().getToNode()
        if node.getType() == UNREGULATED or not _has_logic(node):
            return ()  # unregulated: every crossing link is a foe already (foes)
        mine = self.via_chain(conn)
        line, target = _chain_line(mine), conn.getToLane().getID()
        out = []
        for other in node.getConnections():
            if (other.getFrom() is conn.getFrom() or other.getFromLane().getID().startswith(":")
                    or node.forbids(other, conn)):
                continue
            chain = self.via_chain(other)
            if chain and (other.getToLane().getID() == target or _crosses(_chain_line(chain), line)):
                foe = self._foe(other, chain, mine, upstream=False)
                if foe.approach:
                    out.append(foe)
        return tuple(out)

    def crossers(self, conn) -> tuple[FoeLink, ...]:
        """The links from ``conn``'s own edge -- another lane, another exit lane -- whose internal lanes cross
        its own although neither link gives way to the other in the junction logic, each with its whole
        approach. netconvert joins junctions into clusters whose internal lanes run so (the unseen Sao Paulo
        district: a left turn from the left lane swings across the straight-on from the lane beside it, both
        green at once; SUMO's left-turners drove into the ego twice). SUMO lets both go and its drivers do not
        see the ego there; the ego lets such a car go first (``safety/traffic.py``)."""
        node = conn.getFrom().getToNode()
        if node.getType() == UNREGULATED or not _has_logic(node):
            return ()  # unregulated: every crossing link is a foe already (foes)
        mine = self.via_chain(conn)
        line = _chain_line(mine)
        out = []
        for other in node.getConnections():
            if (other.getFrom() is not conn.getFrom() or other.getFromLane() is conn.getFromLane()
                    or other.getToLane() is conn.getToLane() or node.forbids(other, conn) or node.forbids(conn, other)):
                continue
            chain = self.via_chain(other)
            if chain and _crosses(_chain_line(chain), line):
                out.append(self._foe(other, chain, mine))
        return tuple(out)

    def wait_s(self, conn, path, cum, s_stop_m: float, clear_m: float, half_width_m: float) -> float:
        """Where on the ego's ``path`` (arc lengths ``cum``) a car on ``conn`` waits inside the junction
        for the links with priority that cross it: the farthest arc length from the stop line on whose
        pose (on the path, along its tangent) the front corners of a car ``2 half_width_m`` wide stay
        ``clear_m`` from every such link's path (its internal lanes' centre line) that is farther than that
        at the stop line (one nearer runs beside the entry, not across the way ahead); nan when none
        crosses or there is no room past the stop line."""
        node = conn.getFrom().getToNode()
        if not _has_logic(node):
            return float("nan")
        mine = self.via_chain(conn)
        total = float(sum(ln.getLength() for ln in mine))
        chains = [self.via_chain(o) for o in node.getConnections()
                  if o is not conn and not o.getFromLane().getID().startswith(":") and node.forbids(o, conn)
                  and self._ever_together(conn, o)]
        lines = [_chain_line(c) for c in chains if _conflict_offset(mine, c) < total - 1e-9]
        lines = [ln for ln in lines if ln is not None]
        if not lines:
            return float("nan")
        s = np.arange(s_stop_m, s_stop_m + total, 0.25)
        pts = _front_points(path, cum, s, half_width_m, ahead=True)
        last = len(s) - 1
        for line in lines:  # a foe whose path already passes within clear_m of the stop line runs beside it
            d = shapely.distance(line, pts).reshape(-1, 3).min(axis=1)
            bad = np.flatnonzero(d < clear_m)
            if len(bad) and bad[0] > 0:
                last = min(last, int(bad[0]) - 1)
        return float(s[last]) if last > 0 else float("nan")

    def hold_s(self, conn, path, cum, s_stop_m: float, clear_m: float, half_width_m: float, back_m: float) -> float:
        """Where on the ego's ``path`` a car on ``conn`` waits for the junction: the stop line, or, where the path
        of another link into the junction from another edge (its internal lanes' centre line) passes within
        ``clear_m`` of the front corners (or the front's centre) of a car ``2 half_width_m`` wide standing
        there, the nearest arc length before it at most ``back_m`` back where none does (netconvert's joined
        junctions draw turns over other roads' stop lines: the cars turning there hit a car waiting at its
        line). The stop line itself when no such arc length is found."""
        node = conn.getFrom().getToNode()
        lines = [_chain_line(self.via_chain(o)) for o in node.getConnections()
                 if o.getFrom() is not conn.getFrom() and not o.getFromLane().getID().startswith(":")]
        lines = [ln for ln in lines if ln is not None]
        if not lines:
            return float(s_stop_m)
        s = np.arange(s_stop_m, max(s_stop_m - back_m, 0.0) - 1e-9, -0.25)
        pts = _front_points(path, cum, s, half_width_m, ahead=False)
        d = np.min([shapely.distance(line, pts).reshape(-1, 3).min(axis=1) for line in lines], axis=0)
        ok = np.flatnonzero(d >= clear_m)
        return float(s[ok[0]]) if len(ok) else float(s_stop_m)

    def _ever_together(self, conn, other) -> bool:
        """May ``other`` be open (not red) while ``conn`` has green, by the net's signal programs? True
        when not both are on one light or the net has no program for it (it may come from elsewhere)."""
        tls = conn.getTLSID()
        if not tls or tls != other.getTLSID():
            return True
        programs = self.net.getTLS(tls).getPrograms()
        if not programs:
            return True
        a, b = int(conn.getTLLinkIndex()), int(other.getTLLinkIndex())
        return any(len(ph.state) > max(a, b) and ph.state[a] in "Gg" and ph.state[b] not in "r"
                   for prog in programs.values() for ph in prog.getPhases())

    def gives_way_to(self, lane, conn) -> bool:
        """Does one of the links from ``lane`` (a sumolib lane into ``conn``'s junction) give way to
        ``conn``? (At an unregulated junction nobody gives way.)"""
        node = conn.getFrom().getToNode()
        if node.getType() == UNREGULATED or not _has_logic(node):
            return False
        return any(node.forbids(conn, other) for other in lane.getOutgoing())

    def _foe(self, other, chain, mine, upstream: bool = True) -> FoeLink:
        """``other`` (its internal lanes ``chain``) as a foe of the link whose internal lanes are ``mine``;
        its approach without the lanes before its stop line unless ``upstream``."""
        approach: dict[str, float] = {}
        conflict = _conflict_offset(chain, mine)
        acc = 0.0
        for ln in chain:  # internal lanes up to the conflict point
            if acc > conflict:
                break
            approach[ln.getID()] = conflict - acc
            acc += ln.getLength()
        if upstream:
            self._upstream(other.getFromLane(), conflict + other.getFromLane().getLength(), approach)
        tls = other.getTLSID() or ""
        return FoeLink(tls, int(other.getTLLinkIndex()) if tls else -1, other.getState() or "",
                       other.getDirection() or "", tuple(sorted(approach.items())), float(conflict))

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


def link_state(conn) -> str:
    """The right of way of a connection for the ego: the net's state ('M', 'm', '=', ...), except at
    an unregulated junction, where SUMO gives every link 'M' and nobody yields (its drivers go
    through; it checks no collisions there): '=', the ego gives way to every crossing link
    (:meth:`RightOfWay.foes`)."""
    return "=" if conn.getFrom().getToNode().getType() == UNREGULATED else (conn.getState() or "")


def _has_logic(node) -> bool:
    """Whether sumolib read a junction logic (``<request>`` rows) for ``node``."""
    return bool(getattr(node, "_prohibits", None))


def _front_points(path, cum, s, half_width_m: float, ahead: bool):
    """shapely points, 3 per arc length in ``s``: the front corners (left, right) and the front centre of a car
    ``2 half_width_m`` wide whose front is on ``path`` there, along its tangent over the next (``ahead``) or the
    last half metre."""
    x, y = np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])
    if ahead:
        tx, ty = np.interp(s + 0.5, cum, path[:, 0]) - x, np.interp(s + 0.5, cum, path[:, 1]) - y
    else:
        tx, ty = x - np.interp(s - 0.5, cum, path[:, 0]), y - np.interp(s - 0.5, cum, path[:, 1])
    n = np.hypot(tx, ty)
    nx, ny = -ty / np.maximum(n, 1e-9), tx / np.maximum(n, 1e-9)
    corners = np.column_stack([x + half_width_m * nx, y + half_width_m * ny, x - half_width_m * nx,
                               y - half_width_m * ny, x, y])
    return shapely.points(corners.reshape(-1, 2))


def _crosses(a: LineString | None, b: LineString | None) -> bool:
    return a is not None and b is not None and a.intersects(b)


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
