"""metrics.contacts: how each contact happened, pinned to hand-made poses (an ego 4 m x 2 m at the origin,
heading +x, its front face the segment x = 2, -1 <= y <= 1)."""
import numpy as np
import pandas as pd
import pytest

from sumo_avoid.metrics.contacts import describe


def row(step, vid, x, y, vx=0.0, vy=0.0, length=4.0, width=2.0, heading=0.0, ego=False):
    return {"step": step, "time_s": 0.1 * step, "id": vid, "is_ego": ego, "x": x, "y": y, "vx": vx, "vy": vy,
            "speed": float(np.hypot(vx, vy)), "heading": heading, "length": length, "width": width}


N = 20  # the contact's step (t = 2 s; the jump window reaches back to step 10)


def one(other_rows, ego_speed=5.0, person=False, start=0):
    """The described event of ego E (at step N) and the other party X given by ``other_rows``."""
    ego = [row(s, "E", 0.0, 0.0, vx=ego_speed, ego=True) for s in range(start, N + 1)]
    traj = pd.DataFrame(ego + ([] if person else other_rows))
    persons = pd.DataFrame(other_rows if person else [], columns=list(traj.columns))
    ev = pd.DataFrame([{"step": N, "time_s": 0.1 * N, "a": "E", "b": "X", "x": 0.0, "y": 0.0}])
    return describe(ev, traj, persons, {"E"}).iloc[0]


def steady(x, y, vx=0.0, vy=0.0, **kw):
    """X in the same place over steps 0..N (a still party, or one whose speed covers no motion: no jump)."""
    return [row(s, "X", x, y, vx, vy, **kw) for s in range(0, N + 1)]


def test_front_contact_and_its_impact_speed():
    ev = one(steady(3.9, 0.0, vx=2.0))  # its rear face at x = 1.9: 0.1 m into the ego's front
    assert ev["kind"] == "front"
    assert ev["ego"] == "E"
    assert ev["ego_speed_mps"] == 5.0 and ev["other_speed_mps"] == 2.0
    assert ev["impact_speed_mps"] == pytest.approx(3.0)  # |(5, 0) - (2, 0)|
    assert not ev["other_jumped"]


def test_stopped_ego_comes_first_then_stopped_other():
    assert one(steady(3.9, 0.0, vx=2.0), ego_speed=0.0)["kind"] == "ego_stopped"
    assert one(steady(3.9, 0.0, vx=2.0), ego_speed=0.05)["kind"] == "ego_stopped"  # nuPlan's 0.05 m/s
    ev = one(steady(3.9, 0.0))
    assert ev["kind"] == "other_stopped" and ev["impact_speed_mps"] == pytest.approx(5.0)


def test_rear_and_lateral():
    assert one(steady(-3.9, 0.0, vx=8.0))["kind"] == "rear"  # 180 degrees off the heading
    # centre at 117.8 degrees (atan2(1.9, -1)), its box x in [-3, 1]: clear of the front face x = 2
    ev = one(steady(-1.0, 1.9, vx=6.0))
    assert ev["kind"] == "lateral" and ev["impact_speed_mps"] == pytest.approx(1.0)
    # the same car 3 m further on reaches x = 4: across the front face's end (2, 0.9..1)
    assert one(steady(2.0, 1.9, vx=6.0))["kind"] == "front"


def test_a_person_touching_the_front_face():
    # a disc of radius 0.25 (half its larger side) 0.1 m ahead of the front face, walking across at 1.2 m/s
    ev = one(steady(2.1, 0.0, vy=1.2, length=0.5, width=0.4), person=True)
    assert ev["kind"] == "front"
    assert ev["impact_speed_mps"] == pytest.approx(np.hypot(5.0, 1.2))
    side = one(steady(0.0, 1.2, vy=-1.2, length=0.5, width=0.4), person=True)
    assert side["kind"] == "lateral"


def test_a_party_that_jumped_or_appeared_within_the_second_before():
    walk = steady(2.1, 0.0, vx=-1.2, length=0.5, width=0.4)
    for r in walk[:18]:  # 15.7 m away until step 17, then at the ego's front (as SUMO moves people across a junction)
        r["x"] = 17.8
    assert one(walk, person=True)["other_jumped"]
    walk = steady(2.1, 0.0, vx=-1.2, length=0.5, width=0.4)
    for r in walk[:8]:  # ... the same jump 1.2 s before the contact: outside the window
        r["x"] = 17.8
    assert not one(walk, person=True)["other_jumped"]
    assert one(steady(3.9, 0.0, vx=2.0)[19:])["other_jumped"]  # first recorded at step 19: it appeared
    assert not one(steady(3.9, 0.0, vx=2.0)[5:])["other_jumped"]  # ... at step 5: long before
    gone = steady(3.9, 0.0, vx=2.0)
    del gone[15]  # absent at step 15, back at 16: reappeared within the window
    assert one(gone)["other_jumped"]
    gone = steady(3.9, 0.0, vx=2.0)
    del gone[5]  # ... absent at step 5: long before
    assert not one(gone)["other_jumped"]
    # a run recorded from step 19 on: a party there from its first step did not appear
    assert not one(steady(3.9, 0.0, vx=2.0)[19:], start=19)["other_jumped"]
    # moving 0.5 m per step at 5 m/s is its speed, not a jump
    moving = [row(s, "X", 3.9 - 0.5 * (N - s), 0.0, vx=5.0) for s in range(0, N + 1)]
    assert not one(moving)["other_jumped"]


def test_no_events_gives_the_columns():
    ev = pd.DataFrame(columns=["step", "time_s", "a", "b", "x", "y"])
    out = describe(ev, pd.DataFrame([row(0, "E", 0, 0, ego=True)]), None, {"E"})
    assert out.empty and {"kind", "impact_speed_mps", "other_jumped", "ego"} <= set(out.columns)


def test_a_person_and_a_vehicle_of_one_id_are_told_apart():
    """SUMO keeps persons' and vehicles' ids apart: the event says which one touched the ego."""
    ego = [row(s, "E", 0.0, 0.0, vx=5.0, ego=True) for s in range(N + 1)]
    car = [row(s, "X", 100.0, 100.0, vx=9.0) for s in range(N + 1)]
    person = steady(2.1, 0.0, vy=1.2, length=0.5, width=0.4)
    ev = pd.DataFrame([{"step": N, "time_s": 0.1 * N, "a": "E", "b": "X", "x": 0.0, "y": 0.0}] * 2)
    out = describe(ev, pd.DataFrame(ego + car), pd.DataFrame(person), {"E"}, np.array([True, False]))
    assert out["other_speed_mps"].tolist() == [1.2, 9.0]
    assert out["kind"].tolist() == ["front", "lateral"]
