"""Never stop inside a junction behind a vehicle that cannot leave (issue 34; rules layer).

SUMO's drivers do not enter a junction they could not leave: before a link they check that the lane
beyond it has room for them (``MSVehicle::checkRewindLinkLanes``; junctions are "keep clear" by
default). An ego that entered anyway stood inside the junction behind such a vehicle; on unseen
OpenStreetMap districts the standing ego was then itself a foe inside the junction for the very
vehicle in its way (V2X-TLS district, seed 1: a car waiting at its own stop line with its front 1.25 m
into the ego's path through a joined junction, the ego stopped behind it in the junction, and neither
moved for the remaining 357 s).

The *box* of a link is the ego's path from the link's stop line to where the route leaves the junction
(the start of the first normal lane after it, :func:`junction_exits`). Before the nearest link ahead
the ego is held (the rules' braking curve to ``stop_margin_m`` before the stop line) while

* a vehicle stands (slower than :data:`~sumo_avoid.safety.crossing_rule.QUEUE_MPS`) with its footprint
  within :data:`BOX_MARGIN_M` of the strip the ego's footprint sweeps along the box, and of that strip
  moved to either side as far as the lane's spare width lets the ego move over (:func:`lane_slack`; in
  Wildau a car waiting inside the junction for the ego, at its own internal line, reached 0.08 m into the
  centred strip of a 3.2 m lane: the ego waited for it, it for the ego, for the last 280 s), or
* the exit has not the ego's length plus :data:`~sumo_avoid.safety.crossing_rule.ROOM_M` free
  (:func:`~sumo_avoid.safety.crossing_rule.room_beyond`: vehicles and people standing on the path
  there, or vehicles going its way that would stand there braking now).

People are left to the crossing rule; a vehicle moving in the box clears it. An ego that cannot stop
before the line braking at ``commit_decel_mps2`` goes on; one past its line clears the junction.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from sumo_avoid.core.geometry import footprint_corners, near_any, pairwise_footprint_distance
from sumo_avoid.road.polyline import arc_lengths
from sumo_avoid.safety.crossing_rule import QUEUE_MPS, ROOM_M, room_beyond

#: A standing vehicle this close to the strip the ego sweeps through the junction is in its way, m.
BOX_MARGIN_M = 0.2
#: The strip is tiled by the ego's width at this spacing along the path, m.
BOX_STEP_M = 1.0


def junction_exits(task) -> tuple[float, ...]:
    """Per link of ``task.links``: the arc length where the route leaves its junction (the start of the
    first normal lane piece after the stop line); nan when the path has no lane pieces after it."""
    starts = [p.s_start_m for p in task.lanes if not p.edge.startswith(":")]
    out = []
    for link in task.links:
        after = [s for s in starts if s >= link.s_stop_m - 1e-6]
        out.append(min(after) if after else math.nan)
    return tuple(out)


def _tiles(path: np.ndarray, s_from: float, s_to: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres (K, 2) and headings (K,) of :data:`BOX_STEP_M` tiles along the path from s_from to s_to."""
    cum = arc_lengths(path)
    s = np.arange(s_from + 0.5 * BOX_STEP_M, s_to, BOX_STEP_M)
    if len(s) == 0:
        s = np.array([0.5 * (s_from + s_to)])
    xy = np.column_stack([np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])])
    ahead = np.column_stack([np.interp(s + 0.5, cum, path[:, 0]), np.interp(s + 0.5, cum, path[:, 1])])
    back = np.column_stack([np.interp(s - 0.5, cum, path[:, 0]), np.interp(s - 0.5, cum, path[:, 1])])
    return xy, np.arctan2(ahead[:, 1] - back[:, 1], ahead[:, 0] - back[:, 0])


def _boxes(xy: np.ndarray, heading: np.ndarray, width_m: float, offset_m: float = 0.0) -> np.ndarray:
    if offset_m:
        xy = xy + offset_m * np.column_stack([-np.sin(heading), np.cos(heading)])
    return footprint_corners(xy, heading, BOX_STEP_M + 0.05, width_m)


def strip(path: np.ndarray, s_from: float, s_to: float, width_m: float, offset_m: float = 0.0) -> np.ndarray:
    """(K, 4, 2) boxes of ``width_m`` and :data:`BOX_STEP_M` length tiling the path from s_from to s_to,
    their centres ``offset_m`` to the left of it (negative: to the right)."""
    return _boxes(*_tiles(path, s_from, s_to), width_m, offset_m)


def stands_in_box(path: np.ndarray, s_from: float, s_to: float, snap, ego_row: int, width_m: float,
                  shift_m: float = 0.0) -> bool:
    """Does a vehicle (not a person, not the ego) stand with its footprint within :data:`BOX_MARGIN_M`
    of the strip of ``width_m`` the ego sweeps along the path from s_from to s_to, and of the same strip
    moved ``shift_m`` to either side (as far as the ego can keep off it within its lane: a car waiting at
    its own line with a corner in the lane's middle leaves room to pass it)?"""
    rows = np.flatnonzero(~snap.is_person & (snap.speed < QUEUE_MPS) & (np.arange(snap.n) != ego_row))
    if len(rows) == 0 or s_to <= s_from:
        return False
    xy, heading = _tiles(path, s_from, s_to)
    reach = 0.5 * float(np.hypot(snap.length[rows], snap.width[rows]).max()) + width_m + BOX_STEP_M + shift_m
    rows = rows[near_any(snap.pos[rows], xy, reach)]
    if len(rows) == 0:
        return False
    theirs = footprint_corners(snap.pos[rows], snap.heading[rows], snap.length[rows], snap.width[rows])
    return all((pairwise_footprint_distance(_boxes(xy, heading, width_m + 2.0 * BOX_MARGIN_M, offset), theirs) <= 0.0).any()
               for offset in ((0.0, shift_m, -shift_m) if shift_m > 0.0 else (0.0,)))


def lane_slack(task, s_from: float, s_to: float, width_m: float) -> float:
    """How far the ego (``width_m`` wide) can move off its path to either side and stay within its lane
    along s_from..s_to: half the narrowest lane's width less its own, m (0 without lane pieces)."""
    widths = [p.widths_m[p.lane] for p in task.lanes if p.s_end_m > s_from and p.s_start_m < s_to and p.lane < len(p.widths_m)]
    return max(0.5 * (min(widths) - width_m), 0.0) if widths else 0.0


def box_cap(task, exits, s_front: float, v: float, v_cmd: float, snap, ego_row: int, length_m: float,
            width_m: float, p) -> tuple[float, float]:
    """(speed cap, s of the stop line that sets it) before the nearest link ahead whose box is not
    clear (module doc); (inf, -1) when none holds the ego. ``v_cmd``: the commanded speed (the box is
    not looked at while its cap could not bind)."""
    for link, s_exit in zip(task.links, exits):
        d = link.s_stop_m - s_front
        if d <= 0.0 or s_exit != s_exit:
            continue
        if d > p.lookahead_m or v * v / (2.0 * p.commit_decel_mps2) > d:
            return math.inf, -1.0  # too far to matter yet, or too late to stop: go on
        hold = link.hold_line_m(s_front, v, p.commit_decel_mps2, p.stop_margin_m)  # where it waits
        cap = math.sqrt(2.0 * p.comfort_decel_mps2 * max(hold - s_front - p.stop_margin_m, 0.0))
        if cap > max(v, v_cmd, 0.5):
            return math.inf, -1.0
        need = length_m + ROOM_M
        if (stands_in_box(task.path, link.s_stop_m, s_exit, snap, ego_row, width_m,
                          lane_slack(task, link.s_stop_m, s_exit, width_m))
                or not room_beyond(SimpleNamespace(s_exit_m=s_exit), task.path, snap, ego_row, need)):
            return cap, link.s_stop_m
        return math.inf, -1.0
    return math.inf, -1.0
