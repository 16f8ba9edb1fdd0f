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
