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

The ego, its front bumper d before its stop line at speed v_e, reaches the line in
t_e = max(d - margin, 0) / max(v_e, v_floor). It must yield while a foe arrives within
t_e + t_c + t_margin, t_c the critical gap of its movement (left turns and U-turns
``critical_gap_left_s``, others ``critical_gap_s``; the Highway Capacity Manual's critical headways
for minor-street and roundabout entries lie around 4-7 s, major-street left turns around 4 s; the
defaults 4.5 s / 5 s sit in the 4-5 s the project asks for) and t_margin a safety margin against
foes that speed up. The metric counts a crossing of the stop line as a violation when a foe then
arrives within t_c (without the margin).
"""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.core.types import FoeLink, RouteLink

MAJOR = frozenset("GMO")
CLOSED = frozenset("ru")
V_FLOOR_MPS = 1.0


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


def critical_gap_s(direction: str, gap_s: float, gap_left_s: float) -> float:
    return gap_left_s if direction in ("l", "L", "t") else gap_s


def rows_by_lane(lanes) -> dict[str, list[int]]:
    """Row positions grouped by SUMO lane id (a snapshot's ``lane``, a recording's column; rows
    SUMO has on no lane, "" or missing, are left out)."""
    out: dict[str, list[int]] = {}
    for i, lane in enumerate(lanes):
        if isinstance(lane, str) and lane:
            out.setdefault(lane, []).append(i)
    return out


def foe_arrival(foes: tuple[FoeLink, ...], signals, lanes: dict[str, list[int]], lane_pos, speed, length,
                exclude: set[int]) -> tuple[float, int]:
    """(earliest arrival time t_f at its conflict point of any vehicle of an open foe link, s; its
    row or -1). ``lanes`` maps lane ids to rows of the arrays ``lane_pos``, ``speed``, ``length``."""
    best, who = math.inf, -1
    for foe in foes:
        if link_state(signals, foe.tls, foe.link_index, foe.state) in CLOSED:
            continue
        for lane, offset in foe.approach:
            for r in lanes.get(lane, ()):
                x = offset - float(lane_pos[r])
                if r in exclude or not x > -float(length[r]):
                    continue
                t = max(x, 0.0) / max(float(speed[r]), V_FLOOR_MPS)
                if t < best:
                    best, who = t, r
    return best, who


def ego_time_to_line(d_m: float, v_mps: float, margin_m: float) -> float:
    return max(d_m - margin_m, 0.0) / max(abs(v_mps), V_FLOOR_MPS)


def first_crossing(s: np.ndarray, s_line: float) -> int:
    """Index k of the first step with s[k] < s_line <= s[k+1] (-1 if never)."""
    k = np.flatnonzero((s[:-1] < s_line) & (s[1:] >= s_line))
    return int(k[0]) if len(k) else -1
