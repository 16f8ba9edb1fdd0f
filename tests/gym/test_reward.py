"""The reward's terms on hand-made snapshots (no SUMO): progress, one penalty per contact episode,
off-area distance, comfort, the goal, and the weights' checks."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.gym.reward import RewardTracker, RewardWeights
from sumo_avoid.road.walls import square
from sumo_avoid.rollout.result import Scene


def _snap(t: float, ego_xy, other_xy, speed: float = 10.0, heading: float = 0.0) -> Snapshot:
    pos = np.array([ego_xy, other_xy], float)
    vel = np.array([[speed * np.cos(heading), speed * np.sin(heading)], [0.0, 0.0]])
    return Snapshot(t, ("ego", "car"), pos, vel, np.array([heading, 0.0]), np.array([4.0, 4.0]),
                    np.array([2.0, 2.0]), np.array([True, False]))


def _tracker(**w) -> RewardTracker:
    scene = Scene(None, square((0.0, 0.0), 100.0))
    return RewardTracker(RewardWeights(**w), scene, 0.1, {})


def test_progress_and_one_penalty_per_contact_episode():
    tr = _tracker(progress_per_m=1.0, collision=10.0, jerk_per_mps3_s=0.0, lat_accel_per_mps2_s=0.0)
    r0, _ = tr.step(_snap(0.0, (10, 10), (50, 50)), "ego", 0.0, False)
    r1, t1 = tr.step(_snap(0.1, (11, 10), (50, 50)), "ego", 1.0, False)
    assert r0 == 0.0 and r1 == pytest.approx(1.0) and t1["new_contacts"] == 0
    r2, t2 = tr.step(_snap(0.2, (12, 10), (14, 10)), "ego", 2.0, False)  # footprints overlap
    r3, t3 = tr.step(_snap(0.3, (13, 10), (14, 10)), "ego", 3.0, False)  # still touching: the same contact
    assert (t2["new_contacts"], t3["new_contacts"]) == (1, 0)
    assert r2 == pytest.approx(1.0 - 10.0) and r3 == pytest.approx(1.0)
    _, t4 = tr.step(_snap(0.4, (14, 30), (14, 10)), "ego", 4.0, False)
    _, t5 = tr.step(_snap(0.5, (14, 10.5), (14, 10)), "ego", 5.0, False)  # a new episode
    assert (t4["new_contacts"], t5["new_contacts"]) == (0, 1)


def test_off_area_goal_and_comfort_terms():
    tr = _tracker(progress_per_m=0.0, off_road_per_m_s=2.0, goal=5.0, jerk_per_mps3_s=0.0, lat_accel_per_mps2_s=1.0)
    tr.step(_snap(0.0, (50, 50), (90, 90)), "ego", 0.0, False)
    r, t = tr.step(_snap(0.1, (-3, 50), (90, 90)), "ego", 0.0, False)  # 3 m outside the arena's walls
    assert t["off_road_m"] == pytest.approx(3.0)
    r, t = tr.step(_snap(0.2, (-3, 50), (90, 90), speed=10.0, heading=0.1), "ego", 0.0, True)
    assert t["lat_accel_mps2"] == pytest.approx(10.0 * 0.1 / 0.1)  # v x yaw rate
    assert r == pytest.approx(5.0 - 2.0 * 3.0 * 0.1 - 10.0 * 0.1)


def test_weights_are_finite_and_not_negative():
    with pytest.raises(ValueError, match="collision"):
        RewardWeights(collision=-1.0)
    with pytest.raises(ValueError, match="goal"):
        RewardWeights(goal=float("nan"))
