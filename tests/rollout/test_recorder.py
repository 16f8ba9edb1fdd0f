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


def test_recorded_headings_are_wrapped_to_minus_pi_exclusive_pi_inclusive():
    """SUMO's compass angle 270 deg (west) becomes the math heading -pi, and an integrated heading
    may pass any multiple of 2 pi: trajectories.csv holds (-pi, pi]."""
    raw = np.array([-np.pi, np.pi, -1.5 * np.pi, 2.5 * np.pi, 7.0, -0.1, 0.0])
    s = Snapshot(0.0, tuple(f"v{i}" for i in range(len(raw))), np.zeros((len(raw), 2)), np.zeros((len(raw), 2)), raw,
                 np.full(len(raw), 4.5), np.full(len(raw), 1.8), [True] * len(raw))
    rec = Recorder(0.0)
    rec.record(0, s)
    h = rec.table()["heading"].to_numpy()
    np.testing.assert_allclose(h, [np.pi, np.pi, 0.5 * np.pi, 0.5 * np.pi, 7.0 - 2 * np.pi, -0.1, 0.0], atol=1e-12)
    assert (h > -np.pi).all() and (h <= np.pi).all()


def test_each_id_and_lane_is_held_once_however_many_steps_record_it():
    """SUMO hands out new str objects every step; the recording keeps one object per distinct id and lane id
    (a city hour's recording held tens of millions of copies), and the tables hold the same values."""
    rec = Recorder(0.0)
    for step in range(3):
        ids = tuple("".join(["veh", str(k)]) for k in range(2))  # new objects each step, as from libsumo
        lanes = ["".join(["e1", "_0"]), ""]
        rec.record(step, Snapshot(0.1 * step, ids, np.zeros((2, 2)), np.zeros((2, 2)), np.zeros(2), np.full(2, 4.5),
                                  np.full(2, 1.8), [True, False], lane=lanes))
    first, last = rec._chunks[0], rec._chunks[-1]
    assert first[2][0] is last[2][0] and first[2][1] is last[2][1] and first[9][0] is last[9][0]
    t = rec.table()
    assert list(t["id"]) == ["veh0", "veh1"] * 3 and list(t["lane"]) == ["e1_0", ""] * 3
    assert t["id"].dtype == "str" and t["lane"].dtype == "str"
