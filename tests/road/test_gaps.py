"""Gap acceptance for lane changes (road/gaps.py), pinned to values worked out by hand."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.road.gaps import lane_blockers, lane_is_free, secure_gap_m


def test_secure_gap_by_hand():
    # behind at 25 m/s, ahead at 20: 25 x 1 + (625 - 400) / 9 = 50 m; a slower one behind needs none
    assert secure_gap_m(25.0, 20.0) == pytest.approx(50.0)
    assert secure_gap_m(10.0, 20.0) == 0.0
    assert secure_gap_m(20.0, 0.0) == pytest.approx(20.0 + 400.0 / 9.0)


def test_lane_is_free_by_hand():
    band = (1.75, 5.25)  # lane 2
    one = (np.array([4.5]), np.array([1.8]))
    # ego at s = 100, 20 m/s, 4.5 m long. A car ahead at 20 m/s: room 3 + 20 (secure gap) + 4.5 = 27.5
    assert lane_is_free(100.0, 20.0, 4.5, [[130.0, 3.5]], *one, np.array([20.0]), band)
    assert not lane_is_free(100.0, 20.0, 4.5, [[125.0, 3.5]], *one, np.array([20.0]), band)
    # ... a fellow member there needs only 3 + 1.5 x 0 + 4.5 = 7.5
    assert lane_is_free(100.0, 20.0, 4.5, [[120.0, 3.5]], *one, np.array([20.0]), band, member=[True])
    # a car behind at 25 m/s: room 3 + 50 + 4.5 = 57.5
    assert not lane_is_free(100.0, 20.0, 4.5, [[50.0, 3.5]], *one, np.array([25.0]), band)
    assert lane_is_free(100.0, 20.0, 4.5, [[40.0, 3.5]], *one, np.array([25.0]), band)
    # a member 10 m behind at 25 m/s closes at 5 m/s: room 3 + 7.5 + 4.5 = 15 > 10 -> not free
    assert not lane_is_free(100.0, 20.0, 4.5, [[90.0, 3.5]], *one, np.array([25.0]), band, member=[True])
    # ... the same car in lane 1 (d 0: 0.9 < 1.75 + 0.3) is not in the band -> free
    assert lane_is_free(100.0, 20.0, 4.5, [[90.0, 0.0]], *one, np.array([25.0]), band)
    assert lane_is_free(100.0, 20.0, 4.5, np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0), band)


def test_lane_blockers_are_the_vehicles_lane_is_free_counts():
    # ego at s = 100, 20 m/s: a car ahead 25 m at 20 m/s (room 27.5) blocks, one 30 m ahead does not;
    # one behind at 50 (25 m/s, room 57.5) blocks; one in the ego's own lane (d 0) does not
    band = (1.75, 5.25)
    pos = [[125.0, 3.5], [130.0, 3.5], [50.0, 3.5], [90.0, 0.0]]
    got = lane_blockers(100.0, 20.0, 4.5, pos, np.full(4, 4.5), np.full(4, 1.8), np.array([20.0, 20.0, 25.0, 25.0]), band)
    assert got.tolist() == [True, False, True, False]
    assert lane_blockers(100.0, 20.0, 4.5, np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0), band).shape == (0,)
