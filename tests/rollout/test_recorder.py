"""Recorder: which vehicles are recorded (egos, and others within the recording radius of one)."""
import numpy as np

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.rollout.recorder import Recorder


def test_recorder_keeps_egos_and_vehicles_within_the_radius():
    ids = ("ego", "near", "far")
    s = Snapshot(0.0, ids, [[0.0, 0.0], [0.0, 299.0], [0.0, 301.0]], np.zeros((3, 2)), np.zeros(3), np.full(3, 4.5),
                 np.full(3, 1.8), [True, False, False])
    rec = Recorder(300.0)
    rec.record(0, s)
    assert list(rec.table()["id"]) == ["ego", "near"]
