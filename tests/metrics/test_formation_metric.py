"""S_ef terms (SPEC §3) on hand-made tracks: energy rate, distortion, arrival, obstacle contacts."""
from __future__ import annotations

import math

import numpy as np
import pytest

from sumo_avoid.planning.formation_shape import slots
from sumo_avoid.metrics.formation_score import (
    arrival_time,
    distortion,
    energy_rate,
    obstacle_contacts,
)


def _track(x, y, vx, vy, heading=0.0, length=4.0, width=1.8):
    n = len(x)
    return np.column_stack([x, y, vx, vy, np.full(n, heading), np.full(n, length), np.full(n, width)])


def test_energy_rate_by_hand():
    # one member: v = 0, 1, 2 m/s along x at t = 0, 1, 2: |a| = 1 on both steps, mean speeds 0.5 and 1.5;
    # sum |a||v| dt = 0.5 + 1.5 = 2, path = 2 -> 1 m/s^2, over a_ref 4 -> 0.25
    times = np.array([0.0, 1.0, 2.0])
    tr = _track([0, 0.5, 2], [0, 0, 0], [0, 1, 2], [0, 0, 0])[None]
    assert energy_rate(times, tr, 4.0) == pytest.approx(0.25)
    # constant velocity: no energy
    tr2 = _track([0, 1, 2], [0, 0, 0], [1, 1, 1], [0, 0, 0])[None]
    assert energy_rate(times, tr2, 4.0) == 0.0


def test_distortion_by_hand():
    off = slots("column", 2, 10.0)  # follower 10 m behind; D = 10
    times = np.array([0.0, 1.0])
    lead = _track([0, 0], [0, 0], [0, 0], [0, 0], heading=math.pi / 2)  # facing +y: slot at (0, -10)
    # step 0: follower on its slot; step 1: 3 m off it sideways -> errors 0 and 3, mean 1.5, / 10
    fol = _track([0, 3], [-10, -10], [0, 0], [0, 0])
    assert distortion(np.stack([lead, fol]), off) == pytest.approx(0.15)
    assert arrival_time(times, np.stack([lead, fol]), [(0, 0), (3, -10)], 0.5) == 1.0
    assert arrival_time(times, np.stack([lead, fol]), [(0, 0), (9, 9)], 0.5) is None


def test_obstacle_contacts_count_episodes_and_min_gap():
    square = np.array([[4.0, -1.0], [6.0, -1.0], [6.0, 1.0], [4.0, 1.0]])
    # a 4 m car moving along x through the square: contact from x = 2 to x = 8, then a gap, then again
    x = np.array([0.0, 2.5, 5.0, 7.5, 12.0, 5.0])
    tr = _track(x, np.zeros(6), np.ones(6), np.zeros(6))[None]
    hits, gap = obstacle_contacts(np.arange(6.0), tr, (square,))
    assert hits == 2 and gap == 0.0
    assert obstacle_contacts(np.arange(6.0), tr, ()) == (0, None)
    # the car's front bumper (x + 2) at x = 1.3 and 0.5 is 0.7 and 1.5 m short of the square's face x = 4
    hits, gap = obstacle_contacts(np.arange(2.0), _track([0.5, 1.3], [0, 0], [1, 1], [0, 0])[None], (square,))
    assert hits == 0 and gap == pytest.approx(0.7)
