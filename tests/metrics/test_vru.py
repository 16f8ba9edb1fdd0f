"""metrics/vru.py: hand-computed distances, contact episodes and the smallest VRU gap."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.metrics.vru import (
    cyclist_gaps,
    ego_person_pairs,
    min_gap_vru_m,
    person_contact_events,
    person_radius,
    rectangle_point_distance,
)

COLS = ["step", "time_s", "id", "is_ego", "x", "y", "vx", "vy", "speed", "heading", "length", "width", "lane",
        "lane_pos"]


def _rows(rows):
    return pd.DataFrame([dict(zip(COLS, r)) for r in rows], columns=COLS)


def test_rectangle_point_distance_by_hand():
    # a 4 x 2 car at the origin heading +x: a point 3 m ahead on the axis is 1 m from the front
    assert rectangle_point_distance(0.0, 0.0, 0.0, 4.0, 2.0, 3.0, 0.0) == pytest.approx(1.0)
    # beyond the front-left corner (2, 1) by (3, 4): 5 m
    assert rectangle_point_distance(0.0, 0.0, 0.0, 4.0, 2.0, 5.0, 5.0) == pytest.approx(5.0)
    # the same car turned to +y: the point (0, 3) is 1 m from its front, (3, 0) 2 m from its side
    d = rectangle_point_distance(np.zeros(2), np.zeros(2), np.full(2, np.pi / 2), 4.0, 2.0, [0.0, 3.0], [3.0, 0.0])
    assert d == pytest.approx([1.0, 2.0])
    assert rectangle_point_distance(0.0, 0.0, 0.3, 4.0, 2.0, 0.5, 0.2) == 0.0  # inside


def test_person_radius_is_half_the_larger_side():
    assert person_radius(0.215, 0.478) == pytest.approx(0.239)


def test_person_contacts_are_episodes_and_gaps_are_disc_distances():
    ego = [(k, 0.1 * k, "ego", True, 10.0, 0.0, 0, 0, 0, 0.0, 4.0, 2.0, "", np.nan) for k in range(5)]
    # the person's centre 2.4 m ahead of the ego's centre (0.4 m from its front: no contact, the disc's
    # radius is 0.239 m), then 2.2 and 2.1 (contact), 3.0 (none), 2.0 (contact)
    px = [12.4, 12.2, 12.1, 13.0, 12.0]
    per = [(k, 0.1 * k, "p1", False, px[k], 0.0, 0, 0, 0, np.pi, 0.215, 0.478, "", np.nan) for k in range(5)]
    traj, persons = _rows(ego), _rows(per)
    pairs = ego_person_pairs(traj, persons)
    assert pairs["gap_m"].to_numpy() == pytest.approx(np.array([0.4, 0.2, 0.1, 1.0, 0.0]) - 0.239)
    ev = person_contact_events(traj, pairs)
    assert ev[["step", "a", "b"]].values.tolist() == [[1, "ego", "p1"], [4, "ego", "p1"]]  # episodes 1-2 and 4
    assert ev["x"].tolist() == pytest.approx([11.1, 11.0])
    assert min_gap_vru_m(pairs, np.zeros(0)) == 0.0


def test_no_person_no_pairs_and_no_gap():
    traj = _rows([(0, 0.0, "ego", True, 0.0, 0.0, 0, 0, 0, 0.0, 4.0, 2.0, "", np.nan)])
    pairs = ego_person_pairs(traj, None)
    assert pairs.empty and person_contact_events(traj, pairs).empty
    assert min_gap_vru_m(pairs, cyclist_gaps(traj, {"ego": "passenger"})) is None


def test_cyclist_gap_is_footprint_distance():
    traj = _rows([(0, 0.0, "ego", True, 0.0, 0.0, 0, 0, 0, 0.0, 4.0, 2.0, "", np.nan),
                  (0, 0.0, "bike", False, 0.0, 3.0, 0, 0, 0, 0.0, 1.6, 0.6, "", np.nan),
                  (0, 0.0, "car", False, 0.0, -2.5, 0, 0, 0, 0.0, 4.0, 2.0, "", np.nan)])
    gaps = cyclist_gaps(traj, {"ego": "passenger", "bike": "bicycle", "car": "passenger"})
    assert gaps == pytest.approx([3.0 - 0.3 - 1.0])  # only the bike: 1.7 m between the sides
