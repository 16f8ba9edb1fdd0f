"""The traffic-rules layer at pedestrian crossings (SPEC §6), composed into
:class:`~sumo_avoid.safety.traffic.TrafficRulesLayer`:

* give way: before a crossing the ego's link must give way to (:class:`~sumo_avoid.road.crossings.CrossingLink`
  ``gives_way``: a zebra, or a turn across people who have green at a signalised junction), while a
  person is on it or about to step onto it (:func:`~sumo_avoid.road.crossings.persons_at`), the ego
  stops ``stop_margin_m`` before the crossing's area -- when it can still stop braking at
  ``commit_decel_mps2`` at most; a crossing whose own signal is not green for the people (``G``/``g``)
  is not theirs to cross (:func:`~sumo_avoid.road.crossings.people_may_cross`);
* never stop on a crossing: the ego does not enter a crossing while a vehicle stands (slower than
  :data:`QUEUE_MPS`) on its path within its own length plus :data:`ROOM_M` beyond the crossing.

``cap`` returns (speed cap, arc length of the crossing's entry that sets it), like the layer's other
rules: the cap is the speed from which the ego stops at comfortable braking before the crossing.
"""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.road.crossings import people_may_cross, persons_at
from sumo_avoid.road.polyline import polyline_project_many

QUEUE_MPS = 1.0  # a vehicle slower than this beyond a crossing is standing in a queue, m/s
ROOM_M = 1.0  # the ego enters a crossing only with its length + this free beyond it, m
LANE_HALF_M = 1.6  # a vehicle this close to the ego's path (centre to path) is on it, m


def room_beyond(crossing, path: np.ndarray, snap, ego_row: int, need_m: float) -> bool:
    """Is the ego's path free of standing vehicles for ``need_m`` beyond the crossing?"""
    exit_xy = np.array([np.interp(crossing.s_exit_m, _cum(path), path[:, 0]),
                        np.interp(crossing.s_exit_m, _cum(path), path[:, 1])])
    rows = np.flatnonzero(~snap.is_person & (np.arange(snap.n) != ego_row) & (snap.speed < QUEUE_MPS))
    if len(rows) == 0:
        return True
    near = rows[np.hypot(*(snap.pos[rows] - exit_xy).T) <= need_m + snap.length[rows] + LANE_HALF_M]
    if len(near) == 0:
        return True
    s = polyline_project_many(path, snap.pos[near])
    cum = _cum(path)
    foot = np.column_stack([np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])])
    on_path = np.hypot(*(snap.pos[near] - foot).T) <= LANE_HALF_M
    rear = s - 0.5 * snap.length[near]
    blocking = on_path & (s > crossing.s_exit_m - 0.5) & (rear < crossing.s_exit_m + need_m)
    return not blocking.any()


def _cum(path: np.ndarray) -> np.ndarray:
    return np.r_[0.0, np.cumsum(np.hypot(*np.diff(path, axis=0).T))]


class CrossingRule:
    """Give way at crossings, never stop on one (module doc)."""

    def __init__(self, params):
        self.p = params

    def cap(self, task, s_front: float, v: float, snap, ego_row: int, ego_length_m: float) -> tuple[float, float]:
        p = self.p
        persons = np.flatnonzero(snap.is_person)
        for link in task.links:
            for c in link.crossings:
                d = c.s_enter_m - s_front
                if d <= 0.0:
                    continue  # on it or past it: clear it
                if d > p.lookahead_m:
                    return math.inf, -1.0
                if v * v / (2.0 * p.commit_decel_mps2) > d:
                    continue  # too late to stop before it: go on over it
                stop = math.sqrt(2.0 * p.comfort_decel_mps2 * max(d - p.stop_margin_m, 0.0))
                if c.gives_way and len(persons) and people_may_cross(c, snap.signals):
                    lanes = [snap.lane[r] for r in persons]
                    if persons_at(c, lanes, snap.pos[persons], snap.vel[persons]).any():
                        return stop, c.s_enter_m
                if not room_beyond(c, task.path, snap, ego_row, ego_length_m + ROOM_M):
                    return stop, c.s_enter_m
        return math.inf, -1.0
