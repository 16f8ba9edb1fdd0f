"""The ego's route as the road sees it (static, from the net): the junction links it passes with
their foes and signals, the lanes running the other way beside it, and the lane pieces of its
reference path. Built by :meth:`sumo_avoid.road.network.Road.route_plan`; carried in
:class:`sumo_avoid.core.types.EgoTask`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from sumo_avoid.road.crossings import CrossingLink


@dataclass(frozen=True)
class FoeLink:
    """A junction link with priority over one of the ego's links (they cross or merge), from the
    net's junction logic (static): its signal, and where its vehicles come from."""

    tls: str = ""  # traffic light id, "" = not signalised
    link_index: int = -1  # index into the light's state string
    state: str = ""  # static right of way in the net (M, m, =, ...)
    direction: str = ""  # s, l, r, t, L, R
    approach: tuple[tuple[str, float], ...] = ()  # (SUMO lane id, distance from the lane's start to the conflict point), m
    line_m: float = 0.0  # distance from its stop line (the end of its incoming lane) to the conflict point, m


class OncomingLane(NamedTuple):
    """A lane running the other way beside an edge of the ego's route (from the net, static)."""

    lane: str  # SUMO lane id
    length_m: float
    side: int  # +1 left of the ego's edge, -1 right
    via: tuple[str, ...]  # the internal lanes its connections run over
    gives_way: bool  # one of its links gives way to the ego's link (a car standing there may wait for the ego)


@dataclass(frozen=True)
class RouteLink:
    """A junction link the ego's route passes (from the net, static): where its stop line is on
    the ego's reference path and which signal, if any, controls it."""

    s_stop_m: float  # arc length along EgoTask.path of the stop line (end of the incoming lane), m
    junction: str
    tls: str = ""  # traffic light id, "" = not signalised
    link_index: int = -1  # index into the light's state string (SUMO linkIndex)
    state: str = ""  # the connection's static right of way in the net: M major, m minor, = equal, s stop, ...
    direction: str = ""  # s straight, l left, r right, t turn, L/R partly left/right
    foes: tuple[FoeLink, ...] = ()  # links with priority over this one (sumo.right_of_way)
    # the lane of each edge running opposite to the link's exit edge (into this junction) that borders
    # it; traffic there meets a car whose turn swings wide at the exit (safety.wide_turns)
    oncoming: tuple[OncomingLane, ...] = ()
    leaving: tuple[str, ...] = ()  # the lane bordering the entry edge on each edge leaving the junction the other way
    crossings: tuple[CrossingLink, ...] = ()  # the pedestrian crossings the link passes over (road.crossings)
    # arc length of SUMO's internal junction on the link (where its internal lane is split: a left turn
    # waits there for the oncoming traffic), m; nan when the link has none
    s_wait_m: float = float("nan")
    # links without priority over this one that cross or merge with it, their internal lanes only: a vehicle
    # moving there is in the junction and clears it first (sumo.right_of_way.RightOfWay.inside)
    inside: tuple[FoeLink, ...] = ()
    # where the ego waits for the junction: the stop line, or before it where other links' turns sweep the stop
    # line (right_of_way.RightOfWay.hold_s), m; nan = the stop line
    s_hold_m: float = float("nan")
    # links from the ego's own edge (another lane, another exit) whose internal lanes cross its own though the
    # junction logic makes neither give way (sumo.right_of_way.RightOfWay.crossers): the ego lets them go first
    crossers: tuple[FoeLink, ...] = ()

    def hold_line_m(self, s_front_m: float, v_mps: float, decel_mps2: float, margin_m: float) -> float:
        """The line the ego waits at: :attr:`s_hold_m` when it can still stop ``margin_m`` before it braking at
        ``decel_mps2`` from ``v_mps`` (its front at ``s_front_m``), else the stop line."""
        if self.s_hold_m == self.s_hold_m and self.s_hold_m < self.s_stop_m:
            if v_mps * v_mps / (2.0 * decel_mps2) <= self.s_hold_m - s_front_m - margin_m + 0.5:
                return self.s_hold_m
        return self.s_stop_m

    @property
    def yield_line_m(self) -> float:
        """Where the ego gives way to the link's foes: at a signalised link with an internal junction,
        there (SUMO's drivers enter on green and wait in the junction, and clear it when the light turns
        and the oncoming traffic stops); else at the stop line."""
        return self.s_wait_m if self.tls and self.s_wait_m > self.s_stop_m else self.s_stop_m


@dataclass(frozen=True)
class LanePiece:
    """One piece of the ego's reference path on one SUMO lane (from the net, static): where it is
    on the path and where the other lanes of its edge lie across it (the lanes of the ego's own
    direction; the opposite direction is another edge). Offsets are linear in s over the piece
    (the path blends from one lane to another at the start of an edge)."""

    s_start_m: float  # arc length along EgoTask.path where the piece starts, m
    s_end_m: float  # ... and ends, m
    edge: str  # SUMO edge id (internal ":..." edges inside junctions)
    lane: int  # index of the lane the path follows on this piece
    offsets_start_m: tuple[float, ...]  # d of every lane centre of the edge (by lane index) at s_start, m
    offsets_end_m: tuple[float, ...]  # ... at s_end, m
    widths_m: tuple[float, ...]  # lane widths (by lane index), m
    allowed: tuple[bool, ...] = ()  # may the ego's vehicle class use each lane (by lane index)? () = every lane
    #: width of the oncoming lane beside the edge's leftmost lane (the edge running the other way between
    #: the same junctions) when the ego's class may use it: the lane an overtaking pass borrows, m; 0 = none
    opposite_m: float = 0.0
    opposite_lane: str = ""  # that oncoming lane's id ("" = none)
    opposite_right: bool = False  # that lane lies on the right (left-hand traffic): an oncoming pass does not borrow it
    #: inside a junction: the room (right, left) beyond the internal lane's borders before a sidewalk or
    #: walking area (within the walkway tolerance), the most the corridor may widen there, m; inf = no
    #: walkway near (and on normal edges)
    kerb_room_m: tuple[float, float] = (float("inf"), float("inf"))
    #: on a normal edge: (s, right, left) at sampled arc lengths, how far the corridor's right and left borders
    #: move in where an oncoming lane of another edge overlaps the ego's lanes (:mod:`~sumo_avoid.road.overlaps`),
    #: m; () = none
    narrowing_m: tuple[tuple[float, float, float], ...] = ()

    def usable(self) -> np.ndarray:
        """(lanes,) bool: the lanes the ego may use (its own lane always)."""
        n = len(self.widths_m)
        ok = np.ones(n, bool) if len(self.allowed) != n else np.asarray(self.allowed, bool)
        if 0 <= self.lane < n:
            ok[self.lane] = True
        return ok


def lane_bounds(offsets, widths, usable=None) -> tuple[float, float]:
    """(right, left) bounds, m, of the lanes with centres ``offsets`` and ``widths`` that are ``usable``
    (all when None): the span from the rightmost usable lane's right border to the leftmost's left border."""
    o, w = np.asarray(offsets, float), np.asarray(widths, float)
    ok = np.ones(len(o), bool) if usable is None else np.asarray(usable, bool)
    return float((o - 0.5 * w)[ok].min()), float((o + 0.5 * w)[ok].max())
