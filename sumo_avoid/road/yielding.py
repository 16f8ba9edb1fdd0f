"""Right of way (SPEC §5): gap acceptance at links that must yield, shared by the traffic-rules
layer (which holds the ego) and the ``yield_violations`` metric (which judges the recording).

A link of the ego's route *yields* when its state now is not major: the light's character for a
signalised link ('g' permissive green, 'y'...), the net's static state otherwise ('m' minor,
'=' equal, 's' stop, 'w' all-way stop, 'Z' zipper); 'G', 'M', 'O' have priority and red ('r', 'u')
is the signal part's. Its foes are the links with priority over it (:class:`FoeLink`, from the
junction logic) that are open now (not red).

A foe vehicle is any vehicle on one of a foe link's approach lanes that has not yet passed the
conflict point by its own length: with x the distance of its front bumper to the conflict point
(lane offset - SUMO lane position) and v its speed, it arrives in

    t_f = max(x, 0) / max(v, v_floor)          (v_floor = 1 m/s: a foe standing right at the
                                                conflict point counts as arriving now)

On a signalised foe link, a foe slower than ``START_MPS`` (5 m/s) whose front is within
``AT_LINE_M`` (5 m) of its stop line or past it is setting off from the line (its light turned
green): it arrives as from a standing start, t_f = (sqrt(v^2 + 2 a_f x) - v) / a_f with SUMO's
default passenger acceleration a_f = 2.6 m/s^2: at constant speed (x / max(v, 1 m/s)) a car
standing at its line as its light turns green counts as arriving seconds later than it does. The
rule is not applied at unsignalised links, where it would hold the ego at a roundabout entry for
ring cars slowing near the entry.

A foe that **stands for good** (:func:`stands_for_good`) is no foe: standing still (slower than
``STAND_MPS``) at or behind its stop line for ``standing_foe_wait_s`` (``[layers.traffic]``, 30 s)
or longer, counted from when it came to stand or, on a signalised link, from the last change of its
light if that came later. Such a foe is not coming (blocked, stopped on its lane, waiting for a lane
it cannot reach); SUMO's drivers do not wait for it for ever either (a foe that will not pass
registers no arrival; ``--ignore-junction-blocker``; the junction model's jmIgnoreFoeProb with
jmIgnoreFoeSpeed, which lets a driver ignore foes slower than a speed; impatience growing with the
waiting time over ``--time-to-impatience``; SUMO's "Definition of Vehicles, Vehicle Types, and
Routes", junction model parameters). The moment it moves again it counts again. Not at an all-way
stop or on a link of equal rank (``WAITS_FOR_EGO``): a foe standing there may be waiting for the ego
itself, and the two would set off together (generated grid08, seed 2: after 30 s both went and met).

An **all-way stop** ('w') is first come, first served (:func:`waits_its_turn`). A foe still on its
way to its stop line that can stop before the conflict point (v^2 / (2 * 4.5 m/s^2) <= x, SUMO's
default deceleration) will stop there first: no foe yet. A foe standing more than ``AT_LINE_M``
behind its line is queued: no foe. A foe standing at its line (slower than ``STAND_MPS``) since
after the ego first stood at its own waits its turn: no foe. Every other foe (standing there since
before the ego, setting off from its line within ``DEPART_S``, inside the junction) goes first and
arrives as from a standing start (above): at constant speed a car standing at its line counts
as arriving late and sets off with the ego, while yielding to every standing car leaves the ego and
SUMO's cars (which give the ego its turn) waiting for each other.
"""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.road.route import FoeLink, RouteLink

MAJOR = frozenset("GMO")
CLOSED = frozenset("ru")
V_FLOOR_MPS = 1.0
#: A foe setting off from an all-way stop's line accelerates at this (SUMO's default passenger car), m/s^2.
FOE_START_ACCEL_MPS2 = 2.6
#: Standing: slower than this (SUMO's waiting-time threshold), m/s.
STAND_MPS = 0.1
#: A vehicle whose front is within this of its stop line stands *at* the line, m.
AT_LINE_M = 5.0
#: A foe slower than this within AT_LINE_M of its stop line (or past it) is setting off from it, m/s.
START_MPS = 5.0
#: A foe that stood at its line and set off less than this ago is crossing (not braking to stop), s.
DEPART_S = 5.0
#: Foe links whose vehicles may stand waiting for the ego itself (all-way stop, equal rank): no foe of
#: theirs stands for good (when both went at once after waiting for each other they met: grid08 seed 2).
WAITS_FOR_EGO = frozenset("w=")
#: A standing foe whose front is at most this far past its stop line stands at it (not in the junction), m.
STANDING_PAST_LINE_M = 1.0
#: A foe on its way to an all-way stop's line brakes at most this hard (SUMO's default passenger decel), m/s^2.
FOE_DECEL_MPS2 = 4.5
#: On yellow a foe that can stop before its line braking at most this stops there (SUMO's drivers stop
#: when they can at their decel, 4.5 m/s^2 for a passenger car; judged at less, to be sure), m/s^2.
YELLOW_STOP_DECEL_MPS2 = 3.0


def arrival_time(x_m: float, v_mps: float, starting: bool = False) -> float:
    """When a foe x metres before the conflict point at speed v gets there, s: at constant speed, or
    ``starting`` (setting off from its line) accelerating at FOE_START_ACCEL_MPS2 (module docstring)."""
    x, v = max(float(x_m), 0.0), float(v_mps)
    if starting:
        a = FOE_START_ACCEL_MPS2
        return (math.sqrt(v * v + 2.0 * a * x) - v) / a
    return x / max(v, V_FLOOR_MPS)


def stand_run(time_s, speed) -> tuple[float, float]:
    """(start, end) of the last run of standing (speed < STAND_MPS) in this speed history (time
    order), s; end nan while it still stands, both nan if it never stood."""
    st = np.asarray(speed, float) < STAND_MPS
    last = np.flatnonzero(st)
    if not len(last):
        return math.nan, math.nan
    t = np.asarray(time_s, float)
    moving = np.flatnonzero(~st[:last[-1]])
    end = math.nan if last[-1] == len(st) - 1 else float(t[last[-1] + 1])
    return float(t[moving[-1] + 1 if len(moving) else 0]), end


def link_state(signals, tls: str, link_index: int, static: str) -> str:
    """The state character of a link now: its light's character when signalised, else the net's."""
    if not tls:
        return static
    state = signals.get(tls, "")
    return state[link_index] if 0 <= link_index < len(state) else ""


def yields(link: RouteLink, signals) -> bool:
    """Whether the ego must give way at ``link`` now (it has foes and its state is minor)."""
    c = link_state(signals, link.tls, link.link_index, link.state)
    return bool(link.foes) and c != "" and c not in MAJOR and c not in CLOSED


def critical_gap_s(link: RouteLink, p) -> float:
    """t_c of a link, from the rules parameters ``p``: a zipper merge's headway, a left turn's or
    U-turn's gap, or the gap of other movements."""
    if link.state == "Z":
        return p.zipper_headway_s
    return p.critical_gap_left_s if link.direction in ("l", "L", "t") else p.critical_gap_s


def zipper_slot(t_e: float, arrivals, headway_s: float, gives_way=None) -> float:
    """The earliest time t >= t_e at which the ego can reach a zipper merge with every foe arriving
    at least ``headway_s`` before t, or after t: at least ``headway_s`` after, or at all when the foe
    can give way (``gives_way``, a bool per arrival; default none can). That is t_e itself, or
    ``headway_s`` after one of the foes."""
    a = np.asarray(arrivals, float).reshape(-1)
    g = np.zeros(len(a), bool) if gives_way is None else np.asarray(gives_way, bool).reshape(-1)
    for t in (t_e, *np.sort(a[a + headway_s > t_e] + headway_s)):
        clash = (np.abs(a - t) < headway_s - 1e-9) & ~(g & (a > t))
        if not clash.any():
            return float(t)
    return math.inf  # unreachable: the last candidate is always free


def can_give_way(x_m, v_mps, decel_mps2: float):
    """Whether a foe x metres before the conflict point at speed v could still stop before it
    braking at ``decel_mps2`` (elementwise)."""
    v = np.asarray(v_mps, float)
    return v * v / (2.0 * decel_mps2) <= np.asarray(x_m, float)


def rows_by_lane(lanes) -> dict[str, list[int]]:
    """Row positions grouped by SUMO lane id (a snapshot's ``lane``, a recording's column; rows
    SUMO has on no lane, "" or missing, are left out)."""
    out: dict[str, list[int]] = {}
    for i, lane in enumerate(lanes):
        if isinstance(lane, str) and lane:
            out.setdefault(lane, []).append(i)
    return out


def foe_arrivals(foes: tuple[FoeLink, ...], signals, lanes: dict[str, list[int]], lane_pos, speed, length,
                 exclude: set[int], order=None, standing=None) -> list[tuple[float, int, float]]:
    """(arrival time t_f at its conflict point, s; row; distance x of its front bumper to it, m) of
    every vehicle of an open foe link that has not passed it. ``lanes`` maps lane ids to rows of the
    arrays ``lane_pos``, ``speed``, ``length``. At an all-way stop ``order`` = (now, when the ego
    first stood at its line, history(row) -> (start, end) of the row's last standing run) decides
    who goes first (module docstring); None: every foe there counts. ``standing`` = (now, wait,
    since(row, tls) -> when the row came to stand, or its light ``tls`` last changed if later) leaves
    out the foes that stand for good (:func:`stands_for_good`)."""
    out = []
    for foe in foes:
        state = link_state(signals, foe.tls, foe.link_index, foe.state)
        if state in CLOSED:
            continue
        allway = foe.state == "w"
        yellow = state == "y"
        for r, x in _not_passed(foe, lanes, lane_pos, length, exclude):
            v = float(speed[r])
            if (standing is not None and foe.state not in WAITS_FOR_EGO
                    and stands_for_good(x - foe.line_m, v, *standing, r, foe.tls)):
                continue
            if allway and order is not None and waits_its_turn(x - foe.line_m, x, v, *order, r):
                continue
            if yellow and x - foe.line_m > 0.0 and can_give_way(x - foe.line_m, v, YELLOW_STOP_DECEL_MPS2):
                continue  # on yellow a foe that can stop at its line comfortably stops (SUMO's drivers do)
            # at (or just past) its signal's stop line and slow: it is setting off, not cruising
            starting = allway or (bool(foe.tls) and x - foe.line_m <= AT_LINE_M and v < START_MPS)
            out.append((arrival_time(x, v, starting), r, x))
    return out


def clearing_arrivals(inside: tuple[FoeLink, ...], lanes: dict[str, list[int]], lane_pos, speed, length,
                      exclude: set[int]) -> list[float]:
    """Arrival times at their conflict points of the vehicles moving (at least STAND_MPS) on the internal
    lanes of links without priority (:attr:`~sumo_avoid.road.route.RouteLink.inside`) that have not
    passed them by their length: they are in the junction and clear it first, whatever their light now
    shows; one slower than START_MPS sets off (accelerating as from a standing start). One standing there
    waits (at its internal stop, for the ego): it is no arrival."""
    speeds = ((x, float(speed[r])) for foe in inside for r, x in _not_passed(foe, lanes, lane_pos, length, exclude))
    return [arrival_time(x, v, v < START_MPS) for x, v in speeds if v >= STAND_MPS]


def _not_passed(foe: FoeLink, lanes: dict[str, list[int]], lane_pos, length, exclude: set[int]):
    """(row, distance x of its front bumper to the conflict point, m) of each vehicle on ``foe``'s approach
    lanes, not in ``exclude``, that has not passed the conflict point by its own length."""
    for lane, offset in foe.approach:
        for r in lanes.get(lane, ()):
            x = offset - float(lane_pos[r])
            if r not in exclude and x > -float(length[r]):
                yield r, x


def stands_for_good(to_line_m: float, v_mps: float, now_s: float, wait_s: float, since, row, tls: str) -> bool:
    """Whether a foe (its front ``to_line_m`` before its stop line, at ``v_mps``) stands for good: still
    (slower than STAND_MPS), not inside the junction (at most STANDING_PAST_LINE_M past its line), and
    so for ``wait_s`` or more: ``now_s - since(row, tls)`` (``since``: when it came to stand, or when its
    light last changed if that is later: a car waiting at red sets off at green)."""
    if v_mps >= STAND_MPS or to_line_m < -STANDING_PAST_LINE_M:
        return False
    return now_s - since(row, tls) >= wait_s


def waits_its_turn(to_line_m: float, x_m: float, v_mps: float, now_s: float, ego_first_s: float, history, row) -> bool:
    """At an all-way stop: whether a foe (its front ``to_line_m`` before its stop line, ``x_m``
    before the conflict point, at ``v_mps``) goes after the ego: queued behind its line, standing
    at it since after the ego stood at its own, or still on its way to stop there (it can stop
    before the conflict point and has not just set off from its line)."""
    start, end = history(row)
    if v_mps < STAND_MPS:
        return to_line_m > AT_LINE_M or (to_line_m >= 0.0 and start > ego_first_s)
    just_left = to_line_m <= AT_LINE_M and now_s - end <= DEPART_S
    return to_line_m > 0.0 and bool(can_give_way(x_m, v_mps, FOE_DECEL_MPS2)) and not just_left


def foe_arrival(foes: tuple[FoeLink, ...], signals, lanes: dict[str, list[int]], lane_pos, speed, length,
                exclude: set[int], skip=None, order=None, standing=None) -> tuple[float, int]:
    """(earliest arrival time t_f of :func:`foe_arrivals`, s; its row), or (inf, -1); ``skip(t, row,
    x)`` leaves arrivals out (e.g. zipper foes that can give way)."""
    arr = foe_arrivals(foes, signals, lanes, lane_pos, speed, length, exclude, order, standing)
    return min(((t, r) for t, r, x in arr if skip is None or not skip(t, r, x)), default=(math.inf, -1),
               key=lambda a: a[0])


def ego_time_to_line(d_m: float, v_mps: float, margin_m: float) -> float:
    return max(d_m - margin_m, 0.0) / max(abs(v_mps), V_FLOOR_MPS)


def first_crossing(s: np.ndarray, s_line: float) -> int:
    """Index k of the first step with s[k] < s_line <= s[k+1] (-1 if never)."""
    k = np.flatnonzero((s[:-1] < s_line) & (s[1:] >= s_line))
    return int(k[0]) if len(k) else -1
