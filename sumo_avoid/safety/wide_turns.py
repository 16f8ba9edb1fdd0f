"""Turns a car cannot make inside its lane, and the oncoming traffic they meet (SPEC §5, rules layer).

Where a junction's turn is tighter than the car's turning circle, the car drives the drivable line
(:mod:`sumo_avoid.road.drivable`): wide before the turn, across the apex, and wide again at the
exit, where it may come within a few decimetres of the centre line, or past it. A car following that
line strays from it by up to ``TRACK_ERROR_M`` at the exit, and its corner then sweeps the lane of the
oncoming traffic. A driver of a long vehicle waits at the line until that lane is clear; so does the ego.

For a link whose exit edge has an oncoming lane beside it (``RouteLink.oncoming``), the *wide exit*
is the stretch from 2 m before the exit edge to ``REACH_M`` past it where the line, widened by the
car's half width and ``TRACK_ERROR_M``, crosses the bound of the ego's lanes on that lane's side.
The line is the path of the car's centre: with s_w the last point of the stretch, the car's front
corner reaches s_w + L/2 (L its length), so the conflict point on the oncoming lane lies
e = s_w + L/2 - s_exit before that lane's end (its stop line), and the ego has cleared the wide exit
when its front is at s_clear = s_w + L. An oncoming vehicle x metres before the conflict point at
speed v arrives in max(x, 0) / max(v, 1 m/s) (:func:`~sumo_avoid.road.yielding.arrival_time`;
past that point it is in the ego's sweep until it has left its lane, not only until its rear has
passed the point: a car braking to the end of that lane stays in the sweep). A car that *stands*
past the point waits for the junction. Where one of its lane's links gives way to the ego's
(SUMO's junction logic), it may be waiting for the ego itself: waiting for it would deadlock both;
it is not waited for, and the ego's road view keeps it an obstacle to steer clear of
(control/road_view.py: a vehicle within the room of the drivable line is in the scene). Where none
gives way to the ego's link, it waits for others and stays in the sweep: the ego waits too
(entering beside such a car, the ego would stand inside the turn next to it, with the traffic
behind the ego queueing into the junction). A vehicle queued before the conflict point that has stood still
for the rules' ``standing_foe_wait_s`` does not come (as for the yield rule's foes). The ego, its front at s, clears in
(s_clear - s) / ``TURN_CRAWL_MPS``, the speed it makes such turns at. Before its stop line the ego
is held while an oncoming vehicle arrives before it has cleared, plus the rules' gap margin
(rules.py), and while a car from the oncoming lane is still in the junction (on the internal lanes
its connections run over): it turns or passes next to the ego's wide entry, or has left it by less
than ``LEAVING_CLEAR_M`` on the lane beside the ego's entry (the wide entry closes on such a car
until it is that far away).

The wide *entry* before the stop line keeps to the ego's lane (the line's lane bounds); a car that
passes it on the opposite lane is not waited for.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.road.drivable import REACH_M, drivable_line
from sumo_avoid.road.frenet import RouteFrame
from sumo_avoid.road.route_lanes import RouteLanes
from sumo_avoid.core.types import EgoTask
from sumo_avoid.road.yielding import STAND_MPS, arrival_time, stands_for_good

#: A car may stray this far from its drivable line in a tight turn, m.
TRACK_ERROR_M = 0.5
#: A car makes a turn too tight for it at about this speed, m/s.
TURN_CRAWL_MPS = 2.0
#: The wide exit is looked for from this far before the exit edge, m.
BEFORE_EXIT_M = 2.0
STEP_M = 0.25
#: A car leaving the junction beside the ego's entry is in the way of its wide entry until this far out, m.
LEAVING_CLEAR_M = 12.0


@dataclass(frozen=True)
class WideExit:
    """Where a turn's drivable line sweeps into the oncoming lane of its exit edge."""

    s_clear_m: float  # arc length on the ego's path where its front is when the sweep has ended, m
    # (oncoming lane id, offset of the conflict point on it m, whether a car there may wait for the ego)
    conflicts: tuple[tuple[str, float, bool], ...]
    inside: tuple[str, ...] = ()  # the junction's internal lanes the oncoming lanes lead over
    leaving: tuple[str, ...] = ()  # the lanes leaving the junction beside the ego's entry


def wide_exits(task: EgoTask, turn_radius_m: float) -> dict[int, WideExit]:
    """The wide exits of an ego's route, by position of the link in ``task.links`` (module docstring)."""
    if turn_radius_m <= 0.0 or not task.lanes or not any(lk.oncoming for lk in task.links):
        return {}
    frame = RouteFrame.from_polyline(task.path)
    lanes = RouteLanes(task.lanes)
    line = drivable_line(frame, lanes.corridor, 0.5 * task.width_m, turn_radius_m)
    if not len(line.s):
        return {}
    reach = 0.5 * task.width_m + TRACK_ERROR_M
    out = {}
    for k, link in enumerate(task.links):
        s_exit = next((p.s_start_m for p in task.lanes
                       if p.s_start_m >= link.s_stop_m and not p.edge.startswith(":")), None)
        if not link.oncoming or s_exit is None:
            continue
        s = np.arange(s_exit - BEFORE_EXIT_M, s_exit + REACH_M, STEP_M)
        off = line.offset(s)
        lo, hi = lanes.corridor(s)
        bent = np.abs(off) > 1e-9
        conflicts, ends, inside = [], [], []
        came_by = {p.edge for p in task.lanes if p.s_start_m < link.s_stop_m}
        for onc in link.oncoming:
            if onc.lane.rsplit("_", 1)[0] in came_by:
                continue  # a turnaround: that lane is the ego's own, who is on it is ahead of the ego or follows it
            over = bent & ((off + reach > hi) if onc.side > 0 else (off - reach < lo))
            if over.any():
                end = float(s[np.flatnonzero(over)[-1]]) + STEP_M
                ends.append(end)
                conflicts.append((onc.lane, onc.length_m - max(end + 0.5 * task.length_m - s_exit, 0.0), onc.gives_way))
                inside += onc.via
        if conflicts:
            out[k] = WideExit(max(ends) + task.length_m, tuple(conflicts), tuple(inside), link.leaving)
    return out


def oncoming_first(wide: WideExit, s_front_m: float, lanes: dict[str, list[int]],
                   lane_pos, speed, standing=None, ego_row: int = -1) -> float:
    """(earliest arrival of an oncoming vehicle at the wide exit) - (when the ego has cleared it), s:
    the ego must wait while this is below the gap margin. +inf when no vehicle comes. ``standing`` =
    (now, wait, since(row, tls)) as for :func:`~sumo_avoid.road.yielding.foe_arrivals`: a vehicle that has
    stood still for ``wait`` s or more before the conflict point (queued at its line) does not come; one in
    the sweep, in the junction or just out of it beside the entry still holds the ego (gen_rand08 seed 4:
    released after 30 s, the ego stood inside the junction beside a car standing in its sweep and the car
    behind it ran into it). ``ego_row`` is never a vehicle in the way (at a turnaround the lane it
    stands on is the exit's oncoming lane: unseen Berlin, car56 waited 400 s for itself)."""
    t_clear = max(wide.s_clear_m - s_front_m, 0.0) / TURN_CRAWL_MPS
    if any(r != ego_row for lane in wide.inside for r in lanes.get(lane, ())) or any(
            float(lane_pos[r]) < LEAVING_CLEAR_M and r != ego_row for lane in wide.leaving for r in lanes.get(lane, ())):
        return -np.inf  # a car still crossing the junction or just out of it beside the ego's wide entry
    first = np.inf
    for lane, offset, waits in wide.conflicts:
        for r in lanes.get(lane, ()):
            # past the conflict point it is in the ego's sweep until it has left its lane (then ``inside``),
            # unless it stands there and may wait for the ego (RoadView keeps it an obstacle); one standing for
            # good before the point does not come
            x, v = offset - float(lane_pos[r]), float(speed[r])
            if r != ego_row and (x > 0.0 or v >= STAND_MPS or not waits) and not (
                    x > 0.0 and standing is not None and stands_for_good(x, v, *standing, r, "")):
                first = min(first, arrival_time(x, v))
    return first - t_clear
