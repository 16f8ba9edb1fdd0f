"""Pedestrian crossings on an ego's route (SPEC §6): which crossings a junction link of the route
passes over, where along the ego's path, whether the ego's link must give way to the people on it,
and which persons of a snapshot are on it or about to step onto it.

From the net (static, read once with :mod:`sumolib`, pedestrian connections on):

* a crossing is on a link when its area (the crossing lane's centre line buffered by half its width)
  meets the link's path through the junction; ``s_enter_m`` / ``s_exit_m`` are the arc lengths on the
  ego's reference path where the path enters and leaves that area;
* the ego's link gives way to the crossing when the junction's response for the ego's link has the
  crossing's bit set (``<request response=...>``; a crossing's link index is the position of its lane
  in the junction's ``intLanes``). At a zebra (a crossing with ``priority``) every vehicle link over it
  gives way; at a signalised junction the bit says the link gives way to the people on it *when both
  have green* (a turn across the crossing of its exit arm): the rule applies while the crossing's own
  signal is green (:func:`sumo_avoid.safety.crossing_rule.people_may_cross`);
* the crossing's own signal (its traffic light and link index), "" when it has none.

From a snapshot (dynamic): a person is *on* the crossing when SUMO has it on the crossing's lane, and
*about to step onto it* when it is on one of the crossing's two walking areas within
:data:`KERB_ZONE_M` of the crossing's end and either walks towards the crossing faster than
:data:`APPROACH_MPS` or, at an unsignalised crossing, stands there (a person waiting at the kerb of a
zebra waits for the traffic to stop; at a signalised corner, shared by two crossings, a person who
stands waits for the other crossing's green).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from shapely import contains_xy
from shapely.geometry import LineString

KERB_ZONE_M = 2.0  # a person on a walking area this close to a crossing's end may step onto it, m
APPROACH_MPS = 0.2  # ... when walking towards it faster than this, m/s (or standing)
STAND_MPS = 0.1  # slower than this a person stands, m/s
APPROACH_BAND_M = 3.0  # a person beyond a crossing's end this close to its centre line may walk onto it, m
PEOPLE_GREEN = frozenset("Gg")  # a crossing's signal states in which its people may walk


@dataclass(frozen=True)
class CrossingLink:
    """A pedestrian crossing on the ego's path (from the net, static)."""

    crossing: str  # the crossing's edge id (":J_c0")
    lane: str  # its lane id (persons on it have this lane)
    walking_areas: tuple[str, ...]  # lane ids of the walking areas at its two ends
    ends: tuple[tuple[float, float], ...]  # its centre line's two end points, m
    s_enter_m: float  # arc length on the ego's reference path where the path enters the crossing's area, m
    s_exit_m: float  # ... and leaves it, m
    gives_way: bool  # the ego's link gives way to the people on it (junction logic)
    tls: str = ""  # the crossing's traffic light, "" = not signalised
    link_index: int = -1  # its index in the light's state string
    #: the stretch of the crossing the ego's path passes over: distances from ``ends[0]`` towards
    #: ``ends[1]``, m (the path's centre line; the whole crossing when not known)
    strip: tuple[float, float] = (-np.inf, np.inf)


def link_index(node, conn) -> int:
    """SUMO's link index of a vehicle connection at ``node`` (sumolib counts the incoming lanes'
    connections in order; a crossing's index is the position of its lane in ``intLanes``)."""
    return node.getLinkIndex(conn)


def gives_way(node, mine: int, crossing_index: int) -> bool:
    """Does link ``mine`` give way to link ``crossing_index`` (the response bit of the junction logic)?"""
    response = getattr(node, "_prohibits", {}).get(mine, "")
    return 0 <= crossing_index < len(response) and response[-(crossing_index + 1)] == "1"


def crossing_links(net, conn, path: np.ndarray, cum: np.ndarray, s_from: float, s_to: float) -> tuple[CrossingLink, ...]:
    """The crossings of ``conn``'s junction that the path piece between arc lengths ``s_from`` and
    ``s_to`` (the link through the junction, with some of the lanes either side) passes over."""
    node = conn.getFrom().getToNode()
    internal = node.getInternal()
    mine = link_index(node, conn)
    piece_idx = np.flatnonzero((cum >= s_from - 1e-9) & (cum <= s_to + 1e-9))
    if len(piece_idx) < 2:
        return ()
    lo, hi = max(piece_idx[0] - 1, 0), min(piece_idx[-1] + 1, len(path) - 1)
    piece = LineString(path[lo:hi + 1])
    out = []
    for lane_id in internal:
        if not lane_id.startswith(f":{node.getID()}_c"):
            continue
        lane = net.getLane(lane_id)
        if lane.getEdge().getFunction() != "crossing":
            continue
        shape = np.asarray(lane.getShape(), float)
        area = LineString(shape).buffer(0.5 * lane.getWidth(), cap_style="flat")
        if not piece.intersects(area):
            continue
        s_in, s_out = _span(path[lo:hi + 1], cum[lo:hi + 1], area)
        tls, index, walks = "", -1, []
        for inc in lane.getIncomingConnections():  # from the walking area at its start (with its signal)
            walks.append(inc.getFromLane().getID())
            if inc.getTLSID():
                tls, index = inc.getTLSID(), int(inc.getTLLinkIndex())
        walks += [c.getToLane().getID() for c in lane.getOutgoing()]  # to the walking area at its end
        out.append(CrossingLink(lane.getEdge().getID(), lane_id, tuple(dict.fromkeys(w for w in walks if w != lane_id)),
                                (tuple(map(float, shape[0])), tuple(map(float, shape[-1]))), s_in, s_out,
                                gives_way(node, mine, internal.index(lane_id)), tls, index,
                                _strip(path, cum, s_in, s_out, shape[0], shape[-1])))
    return tuple(sorted(out, key=lambda c: c.s_enter_m))


def _strip(path, cum, s_in: float, s_out: float, a, b) -> tuple[float, float]:
    """The stretch of the crossing from ``a`` to ``b`` that the path passes over between arc lengths
    ``s_in`` and ``s_out``: the path sampled every 0.1 m there, projected on the crossing's axis."""
    axis = np.asarray(b, float) - np.asarray(a, float)
    axis /= max(float(np.hypot(*axis)), 1e-9)
    s = np.arange(s_in, s_out + 0.1, 0.1)
    xy = np.column_stack([np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])])
    u = (xy - np.asarray(a, float)) @ axis
    return float(u.min()), float(u.max())


def _span(points: np.ndarray, cum: np.ndarray, area) -> tuple[float, float]:
    """Arc lengths (on the whole path) where the polyline ``points`` (starting at ``cum[0]``) first
    enters and last leaves ``area``, sampled every 0.1 m."""
    from_s, to_s = float(cum[0]), float(cum[-1])
    s = np.arange(from_s, to_s + 0.1, 0.1)
    x, y = np.interp(s, cum, points[:, 0]), np.interp(s, cum, points[:, 1])
    inside = contains_xy(area, x, y)
    if not inside.any():
        return to_s, to_s
    k = np.flatnonzero(inside)
    return float(s[k[0]]), float(s[k[-1]])


def persons_at(crossing: CrossingLink, lane, pos, vel, half_width_m: float = np.inf, gap_m: float = np.inf,
               horizon_s: float = np.inf, on_only: bool = False) -> np.ndarray:
    """Which persons (rows given by their SUMO lane ids ``lane``, centres ``pos`` (n, 2) and velocities
    ``vel``) are on the crossing or about to step onto it (:mod:`module doc <sumo_avoid.road.crossings>`)
    and not clear of the ego's path: within ``half_width_m`` of the crossing's :attr:`~CrossingLink.strip`,
    or walking towards it from at most ``gap_m`` before it. As SUMO's drivers judge it
    (``MSPModel_Striping::blockedAtDist``: a person past the vehicle's path, or standing beside it,
    does not hold it; SUMO lets a person hold it only after 2 s of standing, here at once). A person
    waiting at a zebra's kerb holds it wherever it stands, and one off the crossing in line with it
    (within :data:`APPROACH_BAND_M` of its centre line, beyond one of its ends) walking onto it holds it
    when its way to the ego's stretch is at most ``gap_m`` (people reach a corner on the sidewalk and
    step on without stopping; one walking along a sidewalk past a crossing's end is not walking onto it).
    With ``horizon_s`` a person walking towards the stretch holds the ego only if it reaches it within
    that time (an ego already over an earlier crossing goes on unless someone will be in its way before
    it is across); with ``on_only`` only the people on the crossing count (its signal has turned: those
    on it finish crossing, the others wait). The defaults: the whole crossing, only who is on it or at its kerb."""
    lane = np.asarray(lane, dtype=object)
    pos, vel = np.asarray(pos, float).reshape(-1, 2), np.asarray(vel, float).reshape(-1, 2)
    on = lane == crossing.lane
    near = np.isin(lane, list(crossing.walking_areas))
    waiting = np.zeros(len(lane), bool)
    if near.any():
        ends = np.asarray(crossing.ends, float)
        d = np.hypot(pos[:, None, 0] - ends[None, :, 0], pos[:, None, 1] - ends[None, :, 1])
        k = d.argmin(axis=1)
        close = d[np.arange(len(pos)), k] <= KERB_ZONE_M
        towards = ends[1 - k] - ends[k]  # from the near end along the crossing
        towards /= np.maximum(np.hypot(towards[:, 0], towards[:, 1]), 1e-9)[:, None]
        speed_in = np.einsum("ij,ij->i", vel, towards)
        standing = np.hypot(vel[:, 0], vel[:, 1]) < STAND_MPS
        # standing at the kerb: waiting for the traffic to stop at a zebra; at a signalised corner, where two
        # crossings meet, a person standing waits for the other crossing's green (on its own green it walks)
        waiting = near & close & (standing if not crossing.tls else np.zeros(len(pos), bool))
        on |= near & close & ((speed_in > APPROACH_MPS) | waiting)
    if np.isinf(half_width_m):
        return on
    ends = np.asarray(crossing.ends, float)
    span = max(float(np.hypot(*(ends[1] - ends[0]))), 1e-9)
    axis = (ends[1] - ends[0]) / span
    u = (pos - ends[0]) @ axis  # along the crossing from its first end, m
    w = vel @ axis  # walking speed along it, m/s
    lo, hi = crossing.strip[0] - half_width_m, crossing.strip[1] + half_width_m
    inside = (u >= lo) & (u <= hi)
    reach = gap_m if np.isinf(horizon_s) else np.minimum(gap_m, horizon_s * np.abs(w))  # how far before the stretch a walker still holds the ego
    coming = ((w > APPROACH_MPS) & (u < lo) & (lo - u <= reach)) | ((w < -APPROACH_MPS) & (u > hi) & (u - hi <= reach))
    if on_only:
        return (lane == crossing.lane) & (inside | coming)
    held = on & (inside | coming | waiting)
    # off the crossing, walking towards one of its ends (along a sidewalk, over a corner): held when the
    # walk to that end and on along the crossing to the ego's stretch is at most gap_m (they may cross)
    rest = ~on & (lane != crossing.lane)
    if rest.any():
        across = np.abs((pos - ends[0]) @ np.array([-axis[1], axis[0]]))  # from the crossing's centre line, m
        before = rest & (u < 0.0) & (w > APPROACH_MPS) & (max(lo, 0.0) - u <= reach)
        beyond = rest & (u > span) & (w < -APPROACH_MPS) & (u - min(hi, span) <= reach)
        held |= (before | beyond) & (across <= APPROACH_BAND_M)
    return held


def people_may_cross(crossing: CrossingLink, signals) -> bool:
    """The crossing is the people's to cross now: unsignalised, or its signal green for them."""
    if not crossing.tls:
        return True
    state = signals.get(crossing.tls, "")
    return 0 <= crossing.link_index < len(state) and state[crossing.link_index] in PEOPLE_GREEN


def stands_on_crossing(links, s_front_m: float, s_line_m: float, length_m: float) -> bool:
    """Would a car ``length_m`` long, its front at ``s_front_m`` now, standing at the stop line ``s_line_m``
    stand on a crossing it has already entered (a crossing that ends within its length before the line)?
    Then no lawful stop is left at that line: at a yellow it clears the crossing and goes on (wildau_turns,
    radar, seed 1: a light 2.9 m beyond a junction's crossing turned yellow while the ego was on it)."""
    return any(c.s_enter_m <= s_front_m and s_line_m - length_m < c.s_exit_m <= s_line_m
               for lk in links for c in lk.crossings)
