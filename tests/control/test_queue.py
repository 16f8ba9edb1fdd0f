"""When the vehicle standing ahead is queued (control/apf/queue.py), on hand-made route-frame scenes:
the ego's path with a stop line at s = 100 m, the ego (4.8 m) at s = 60 m, d = 0."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.control.apf.queue import queued_ahead, waits_in_queue
from sumo_avoid.control.road_view import FrenetScene


def _scene(cars, ego_d=0.0):
    """``cars``: (s, d, speed) of 4.5 m cars."""
    pos = np.array([[s, d] for s, d, _ in cars], float).reshape(-1, 2)
    vel = np.array([[v, 0.0] for _, _, v in cars], float).reshape(-1, 2)
    n = len(pos)
    return FrenetScene(60.0, ego_d, 0.0, np.zeros(2), 4.8, 1.8, pos, np.zeros(n), np.full(n, 4.5), np.full(n, 1.8), vel,
                       lambda s: (np.full(len(s), -1.6), np.full(len(s), 1.6)))


@pytest.mark.parametrize("cars, queued", [
    ([(97.0, 0.0, 0.0)], True),  # the first at the line: its front 99.25, 0.75 m before it
    ([(80.0, 0.0, 0.0)], False),  # its front 17.75 m before the line: more than 15 m
    # a chain: 80 (front 82.25), 88.5 (rear 86.25: 4 m behind it), 97 (rear 94.75: 6.25 m): queued
    ([(80.0, 0.0, 0.0), (88.5, 0.0, 0.0), (97.0, 0.0, 0.0)], True),
    ([(80.0, 0.0, 0.0), (97.0, 0.0, 0.0)], False),  # 12.5 m bumper to bumper: more than the chain's 8 m
    ([(80.0, 0.0, 0.0), (88.5, 0.0, 3.0), (97.0, 0.0, 0.0)], False),  # the middle one moves: the chain ends
    # moving off from the line at 1.1 and 2.3 m/s (below CREEP_MPS): still a queue (lyon_unseen, seed 1)
    ([(80.0, 0.0, 0.0), (88.5, 0.0, 1.1), (97.0, 0.0, 2.3)], True),
    ([(80.0, 0.0, 1.1), (88.5, 0.0, 0.0), (97.0, 0.0, 0.0)], False),  # the one just ahead still moves: no queue yet
    ([(97.0, 0.0, 2.0)], False),  # the one ahead moves
    ([(97.0, 3.2, 0.0)], False),  # in the next lane
    ([(50.0, 0.0, 0.0)], False),  # behind the ego
])
def test_a_queue_is_a_chain_of_standing_cars_whose_first_stands_near_a_stop_line(cars, queued):
    assert queued_ahead(_scene(cars), [100.0], 15.0) == queued


def test_the_ego_waits_in_a_queue_only_for_its_patience():
    class Link:
        s_stop_m = 100.0

    class Task:
        links = (Link(),)

    sc = _scene([(97.0, 0.0, 0.0)])
    assert waits_in_queue(sc, Task(), 500.0, 29.9, 15.0, 30.0)
    assert not waits_in_queue(sc, Task(), 500.0, 30.0, 15.0, 30.0)
    # the path's end counts as a stop line (the goal at the end of the route's last edge)
    sc_end = _scene([(167.0, 0.0, 0.0)])
    assert waits_in_queue(sc_end, Task(), 170.0, 0.0, 15.0, 30.0)
    assert not waits_in_queue(sc_end, Task(), 500.0, 0.0, 15.0, 30.0)


def test_the_chain_ahead_ends_where_the_gap_opens():
    """The ego's front at 62.4 m. Cars (4.5 m) at 68 (rear 65.75: 3.35 m ahead), 76 (rear 73.75: 3.5 m behind
    the first's front 70.25), 90 (rear 87.75: 9.5 m behind 78.25, more than CHAIN_GAP_M): the chain ends at
    78.25, moving or not; a car in the next lane is no link."""
    from sumo_avoid.control.apf.queue import chain_end_s

    assert chain_end_s(_scene([(68.0, 0.0, 3.0), (76.0, 0.0, 0.0), (90.0, 0.0, 0.0), (72.0, 3.2, 0.0)])) == 78.25
    assert chain_end_s(_scene([(75.0, 0.0, 0.0)])) == 62.4  # its rear 72.75: 10.35 m ahead
    assert chain_end_s(_scene([])) == 62.4


class _View:
    """A two-lane corridor [-1.6, 4.8] that narrows to the ego's lane [-1.6, 1.6] from s = ``ends``."""

    def __init__(self, ends):
        self.ends, self.length_m = ends, 500.0

    def corridor(self, s):
        s = np.asarray(s, float)
        return np.full(len(s), -1.6), np.where(s < self.ends, 4.8, 1.6)


@pytest.mark.parametrize("ends, runs_past", [(200.0, True), (93.0, True), (92.0, False), (70.0, False)])
def test_an_escape_lane_must_run_past_the_traffic_it_passes(ends, runs_past):
    """Chain end 78.25 (above) + the ego's 4.8 m + CHAIN_GAP_M 8 m = 91.05: the next lane (centre 3.2 m, a
    1.8 m car needs hi >= 4.1) must be there at every metre from the ego's 60 m to 92 m (the first sample
    past 91.05): a lane that narrows from 93 m does, one from 92 m does not."""
    from sumo_avoid.control.apf.queue import lane_runs_past

    sc = _scene([(68.0, 0.0, 3.0), (76.0, 0.0, 0.0), (90.0, 0.0, 0.0)])
    assert lane_runs_past(_View(ends), sc, 3.2) == runs_past
    assert lane_runs_past(_View(ends), sc, 0.0)  # the ego's own lane always runs on


@pytest.mark.parametrize("length_m, speed, runs_past", [
    (500.0, 4.5, True),  # the path runs on: the lane runs past
    (91.0, 4.5, False),  # the path ends at 91 m, before 91.05: moving, no lane past the chain
    (92.0, 4.5, True),  # ends just after it
    (91.0, 0.0, True),  # standing, it may (it backs up for the room first)
])
def test_no_escape_at_speed_where_the_path_ends_before_the_lane_runs_past(length_m, speed, runs_past):
    """The chain above ends at 78.25; past it means 91.05 (78.25 + 4.8 + CHAIN_GAP_M). A moving ego whose path (its
    goal) ends before that would stop at the end with its lane change half done (bologna_bus_lane, seed 3)."""
    from sumo_avoid.control.apf.queue import lane_runs_past

    sc = _scene([(68.0, 0.0, 3.0), (76.0, 0.0, 0.0), (90.0, 0.0, 0.0)])
    sc = FrenetScene(sc.s, sc.d, sc.heading, np.array([speed, 0.0]), sc.length, sc.width, sc.o_pos, sc.o_heading,
                     sc.o_length, sc.o_width, sc.o_vel, sc.corridor)
    view = _View(200.0)
    view.length_m = length_m
    assert lane_runs_past(view, sc, 3.2) == runs_past
