"""The traffic-rules layer at pedestrian crossings (SPEC §6), composed into
:class:`~sumo_avoid.safety.traffic.TrafficRulesLayer`:

* give way: before a crossing the ego's link must give way to (:class:`~sumo_avoid.road.crossings.CrossingLink`
  ``gives_way``: a zebra, or a turn across people who have green at a signalised junction), while a
  person is on it or about to step onto it (:func:`~sumo_avoid.road.crossings.persons_at`), the ego
  stops ``stop_margin_m`` before the crossing's area -- when it can still stop braking at
  ``commit_decel_mps2`` at most; a crossing whose own signal is not green for the people (``G``/``g``)
  is not theirs to cross (:func:`~sumo_avoid.road.crossings.people_may_cross`);
* never stop on a crossing: the ego does not enter a crossing while a vehicle or a person stands (slower
  than :data:`QUEUE_MPS`) on its path within its own length plus :data:`ROOM_M` beyond the crossing, or a
  vehicle going its way would stand there braking at :data:`LEAD_DECEL_MPS2` (a queue forming), or a
  light not green holds it at a stop line there (:func:`light_beyond`), and
  when it waits before a crossing where it would stand on an earlier one (a turn over the crossings
  of its entry and exit arms, a car length apart or less) it waits before the earlier one.

A person holds the ego as SUMO's drivers judge it: on the crossing or stepping onto it, and within
``crossing_margin_m`` of the footprint's side where the ego's path passes over the crossing, or
walking towards that stretch from at most ``crossing_gap_m`` (:func:`~sumo_avoid.road.crossings.persons_at`).

``cap`` returns (speed cap, arc length of the crossing's entry that sets it), like the layer's other
rules: the cap is the speed from which the ego stops at comfortable braking before the crossing.
"""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.road.crossings import people_may_cross, persons_at
from sumo_avoid.road.polyline import polyline_project_many
from sumo_avoid.road.regulation import RED
from sumo_avoid.road.yielding import link_state

RED_OR_YELLOW = RED | frozenset("yY")  # a light beyond a crossing that will hold the ego (road.regulation)
QUEUE_MPS = 1.0  # a vehicle slower than this beyond a crossing is standing in a queue, m/s
# the ego enters a crossing (junction_box: a junction) only with its length + this free beyond it, m: the gap a car
# keeps to a standing one (APF-SA's governor 2.0 m, SUMO's default minGap 2.5 m). With 1.0 m, berlin_eastbound
# seed 6 (truth) entered behind a car standing 6 m beyond a crossing and stood 0.5 m on it, 2 m behind the car.
ROOM_M = 2.5
LANE_HALF_M = 1.6  # a vehicle this close to the ego's path (centre to path) is on it, m
LEAD_DECEL_MPS2 = 4.5  # a vehicle ahead beyond a crossing could stop braking this hard (SUMO's default decel), m/s^2
CLEAR_ACCEL_MPS2 = 1.5  # an ego over a crossing clears the next one speeding up at least this, m/s^2


def room_beyond(crossing, path: np.ndarray, snap, ego_row: int, need_m: float) -> bool:
    """Is the ego's path free for ``need_m`` beyond the crossing, of vehicles and people standing there and
    of vehicles going the path's way that would stand there if they braked now at :data:`LEAD_DECEL_MPS2`
    (a queue forming: the car ahead still slowing down; SUMO's drivers judge a junction's exit by the
    leader's brake gap the same way)? (People waiting at a corner stand where SUMO's walking area meets the
    road, which a tight turn sweeps.)"""
    cum = _cum(path)
    exit_xy = np.array([np.interp(crossing.s_exit_m, cum, path[:, 0]), np.interp(crossing.s_exit_m, cum, path[:, 1])])
    others = np.arange(snap.n) != ego_row
    stop_gap = np.where(snap.is_person, 0.0, snap.speed**2 / (2.0 * LEAD_DECEL_MPS2))
    reach = need_m + snap.length + LANE_HALF_M
    rows = np.flatnonzero(others & ((snap.speed < QUEUE_MPS) | (stop_gap < reach)))
    if len(rows) == 0:
        return True
    near = rows[np.hypot(*(snap.pos[rows] - exit_xy).T) <= reach[rows]]
    if len(near) == 0:
        return True
    s = polyline_project_many(path, snap.pos[near])
    foot = np.column_stack([np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])])
    on_path = np.hypot(*(snap.pos[near] - foot).T) <= LANE_HALF_M
    # a moving one counts where its brake gap ends, if it goes the path's way (within 45 degrees of it)
    k = np.clip(np.searchsorted(cum, s) - 1, 0, len(path) - 2)
    tangent = path[k + 1] - path[k]
    along = np.einsum("ij,ij->i", snap.vel[near], tangent) / np.maximum(np.hypot(*tangent.T), 1e-9)
    standing = snap.speed[near] < QUEUE_MPS
    slowing = ~standing & ~snap.is_person[near] & (along >= np.cos(np.pi / 4) * snap.speed[near])
    rear = s - 0.5 * snap.length[near] + np.where(slowing, stop_gap[near], 0.0)
    blocking = on_path & (standing | slowing) & (s > crossing.s_exit_m - 0.5) & (rear < crossing.s_exit_m + need_m)
    return not blocking.any()


def light_beyond(crossing, links, signals, need_m: float) -> bool:
    """Does a signal that is not green (red, red-yellow or yellow) hold the ego at a stop line within
    ``need_m`` beyond the crossing? It would stand with its rear on the crossing (wildau_turns, radar,
    seed 1: a 4 m edge between a junction's crossing and the next junction's light)."""
    return any(link.tls and crossing.s_exit_m - 0.5 < link.s_stop_m <= crossing.s_exit_m + need_m
               and link_state(signals, link.tls, link.link_index, link.state) in RED_OR_YELLOW for link in links)


def _cum(path: np.ndarray) -> np.ndarray:
    return np.r_[0.0, np.cumsum(np.hypot(*np.diff(path, axis=0).T))]


class CrossingRule:
    """Give way at crossings, never stop on one (module doc)."""

    def __init__(self, params):
        self.p = params

    def cap(self, task, s_front: float, v: float, snap, ego_row: int, ego_length_m: float,
            ego_width_m: float = 1.8) -> tuple[float, float]:
        p = self.p
        persons = np.flatnonzero(snap.is_person)
        crossings = [c for link in task.links for c in link.crossings]
        for i, c in enumerate(crossings):
            d = c.s_enter_m - s_front
            if d <= 0.0:
                continue  # on it or past it: clear it
            if d > p.lookahead_m:
                return math.inf, -1.0
            if v * v / (2.0 * p.commit_decel_mps2) > d:
                continue  # too late to stop before it: go on over it
            # already over an earlier crossing it would stand on while waiting: it goes on unless someone
            # will be in its way before it is across
            over = any(b.s_enter_m <= s_front and s_front - ego_length_m - p.stop_margin_m < b.s_exit_m
                       for b in crossings[:i])
            horizon = self._time_to_clear(c, s_front, v, ego_length_m) if over else math.inf
            if self._blocked(c, task, snap, ego_row, persons, ego_length_m, ego_width_m, horizon):
                line = self._wait_line(crossings[:i], c.s_enter_m, s_front, v, ego_length_m)
                return math.sqrt(2.0 * p.comfort_decel_mps2 * max(line - s_front - p.stop_margin_m, 0.0)), line
        return math.inf, -1.0

    def _time_to_clear(self, c, s_front: float, v: float, ego_length_m: float) -> float:
        """Time until the ego's rear leaves crossing ``c`` speeding up at ``clear_accel_mps2`` from ``v``."""
        dist = c.s_exit_m + ego_length_m - s_front
        a = CLEAR_ACCEL_MPS2
        return (-v + math.sqrt(v * v + 2.0 * a * max(dist, 0.0))) / a

    def _blocked(self, c, task, snap, ego_row, persons, ego_length_m, ego_width_m, horizon_s=math.inf) -> bool:
        p = self.p
        if c.gives_way and len(persons):
            lanes = [snap.lane[r] for r in persons]
            # on the people's green: anyone on it or about to cross; after it: those still on it
            if persons_at(c, lanes, snap.pos[persons], snap.vel[persons], 0.5 * ego_width_m + p.crossing_margin_m,
                          p.crossing_gap_m, horizon_s, on_only=not people_may_cross(c, snap.signals)).any():
                return True
        return (not room_beyond(c, task.path, snap, ego_row, ego_length_m + ROOM_M)
                or light_beyond(c, task.links, snap.signals, ego_length_m + ROOM_M))

    def _wait_line(self, before, line: float, s_front: float, v: float, ego_length_m: float) -> float:
        """Where the ego waits for crossing entry ``line``: before it, or before an earlier crossing
        (``before``, in path order) it would otherwise stand on, if it can still stop there."""
        for c in reversed(before):
            stand_rear = line - self.p.stop_margin_m - ego_length_m
            d = c.s_enter_m - s_front
            if c.s_enter_m < line and stand_rear < c.s_exit_m and d > 0 and v * v / (2.0 * self.p.commit_decel_mps2) <= d:
                line = c.s_enter_m
        return line
