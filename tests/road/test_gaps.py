"""Gap acceptance for lane changes (road/gaps.py), pinned to values worked out by hand."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.road.gaps import lane_blockers, lane_change_length_m, lane_is_free, secure_gap_m


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


def test_lane_change_length_by_hand():
    # R 4.25 m: a shift of R (2 - sqrt 2) takes two 45 deg arcs, 2R sin 45 = R sqrt 2 along the road;
    # a shift of 2R two quarter circles, 2R; more cannot be had in less than 2R; no radius, no length
    assert lane_change_length_m(4.25 * (2.0 - np.sqrt(2.0)), 4.25) == pytest.approx(4.25 * np.sqrt(2.0), rel=1e-12)
    assert lane_change_length_m(-8.5, 4.25) == pytest.approx(8.5, rel=1e-12)
    assert lane_change_length_m(12.0, 4.25) == pytest.approx(8.5, rel=1e-12)
    assert lane_change_length_m(3.2, 0.0) == 0.0 and lane_change_length_m(0.0, 4.25) == 0.0


def test_a_standing_car_ahead_in_the_lane_needs_the_room_the_move_takes():
    # Bologna: the ego standing, a car standing in the next lane 13 m ahead (centres): room 3 + 0 + 5 = 8
    # without the move; the move of 6.01 m at R 4.25 m (shift 2.49 m) makes it 14.01 > 13: blocked
    band, one = (1.75, 5.25), (np.array([5.0]), np.array([1.8]))
    move = lane_change_length_m(4.25 * (2.0 - np.sqrt(2.0)), 4.25)
    assert lane_is_free(100.0, 0.0, 5.0, [[113.0, 3.5]], *one, np.array([0.0]), band)
    assert not lane_is_free(100.0, 0.0, 5.0, [[113.0, 3.5]], *one, np.array([0.0]), band, move_m=move)
    assert lane_is_free(100.0, 0.0, 5.0, [[114.1, 3.5]], *one, np.array([0.0]), band, move_m=move)
    # one driving away at least as fast as the ego is not closed on during the move: the room as before
    # (ego 10 m/s, it 10 m/s: 3 + 10 x 1 (secure gap) + 5 = 18 m)
    assert lane_is_free(100.0, 10.0, 5.0, [[118.5, 3.5]], *one, np.array([10.0]), band, move_m=move)
    assert not lane_is_free(100.0, 10.0, 5.0, [[117.5, 3.5]], *one, np.array([10.0]), band, move_m=move)
    # ... one behind never needs it (a car 9 m behind at 0 m/s, the ego at 0: 3 + 0 + 5 = 8 < 9)
    assert lane_is_free(100.0, 0.0, 5.0, [[91.0, 3.5]], *one, np.array([0.0]), band, move_m=move)
