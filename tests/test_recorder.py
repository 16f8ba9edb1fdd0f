"""Recorder: which vehicles are recorded (egos, and others within the recording radius of one)."""
import numpy as np
from scipy.spatial import cKDTree

from sumo_avoid.recorder import Recorder, near_any
from sumo_avoid.snapshot import Snapshot


def test_near_any_hand_values():
    centres = np.array([[0.0, 0.0], [100.0, 0.0]])
    points = np.array([[3.0, 4.0], [5.0, 0.0001], [50.0, 0.0], [103.0, -4.0], [0.0, 5.0]])
    # distances to the nearer centre: 5, 5.000000001, 50, 5, 5
    assert near_any(points, centres, 5.0).tolist() == [True, False, False, True, True]
    assert near_any(points, centres, 50.0).tolist() == [True, True, True, True, True]
    assert near_any(points, centres[:0], 5.0).tolist() == [False] * 5


def test_near_any_equals_the_kdtree_answer():
    """The sweep settles most points; the rest go to the k-d tree: together the k-d tree's answer,
    on random layouts (points far from every centre along the sweep axis included) and a road along y."""
    rng = np.random.default_rng(3)
    for k in range(300):
        n, m = int(rng.integers(1, 300)), int(rng.integers(1, 40))
        scale = rng.uniform(1, 1000, 2)
        p, c = rng.uniform(0, 1, (n, 2)) * scale, rng.uniform(0, 1, (m, 2)) * scale
        r = float(rng.uniform(0, 300))
        ref = cKDTree(c).query(p, k=1, distance_upper_bound=r * (1 + 1e-9))[0] <= r
        assert np.array_equal(near_any(p, c, r), ref), k


def test_recorder_keeps_egos_and_vehicles_within_the_radius():
    ids = ("ego", "near", "far")
    s = Snapshot(0.0, ids, [[0.0, 0.0], [0.0, 299.0], [0.0, 301.0]], np.zeros((3, 2)), np.zeros(3), np.full(3, 4.5),
                 np.full(3, 1.8), [True, False, False])
    rec = Recorder(300.0)
    rec.record(0, s)
    assert list(rec.table()["id"]) == ["ego", "near"]
