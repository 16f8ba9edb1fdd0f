"""Hand-computed checks for sumo_avoid.metrics.basic (m, s, rad)."""
import math

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.metrics.basic import (
    F1,
    F2,
    F3,
    braking_curve_D,
    collision_events,
    fitness,
    min_gap_m,
    motion_summary,
    phi_coll,
    phi_wall,
    transfer_S,
)

DT = 0.5


def row(step, vid, ego, x, y, speed=0.0, heading=0.0, length=4.0, width=2.0):
    return dict(step=step, time_s=step * DT, id=vid, is_ego=ego, x=float(x), y=float(y),
                vx=speed * math.cos(heading), vy=speed * math.sin(heading), speed=float(speed),
                heading=heading, length=length, width=width)


def table(rows):
    return pd.DataFrame(rows)


# ------------------------------------------------------------------ collisions
def test_collision_episodes():
    rows = []
    for s in range(11):
        rows.append(row(s, "e1", True, 0, 0))  # x in [-2,2]
        # c1 at x=3 (x in [1,5]) overlaps e1 on steps 3-5 and 8-9, far away otherwise
        rows.append(row(s, "c1", False, 3 if s in (3, 4, 5, 8, 9) else 20, 0))
        # two non-egos overlapping all the time: never an event
        rows.append(row(s, "n1", False, 100, 0))
        rows.append(row(s, "n2", False, 101, 0))
        # ego vs ego: e3 at y=51.5 overlaps e2 at y=50 (widths 2: |dy|=1.5 < 2) on step 0 only
        rows.append(row(s, "e2", True, 0, 50))
        rows.append(row(s, "e3", True, 0, 51.5 if s == 0 else 80))
    ev = collision_events(table(rows))
    assert list(ev.columns) == ["step", "time_s", "a", "b", "x", "y"]
    assert len(ev) == 3
    assert ev[["step", "a", "b"]].values.tolist() == [[0, "e2", "e3"], [3, "c1", "e1"], [8, "c1", "e1"]]
    # midpoints of the centres at the first contact step: (0,50.75), (1.5,0), (1.5,0)
    np.testing.assert_allclose(ev[["x", "y"]].to_numpy(float), [[0, 50.75], [1.5, 0], [1.5, 0]])
    np.testing.assert_allclose(ev["time_s"].to_numpy(float), [0.0, 1.5, 4.0])


def test_collision_rotated_no_contact_and_empty():
    # e at origin heading pi/4, 4x2; c centred (2.5,-2.5) heading pi/4: along e's left axis
    # (-s,s) the centre offset is -2.5*sqrt2 = -3.54 > half widths 1+1 -> apart, although the
    # centre distance 3.54 < half-diagonal sum 2*sqrt5 = 4.47 (passes the broad phase)
    h = math.pi / 4
    t = table([row(0, "e", True, 0, 0, heading=h), row(0, "c", False, 2.5, -2.5, heading=h)])
    assert len(collision_events(t)) == 0
    assert len(collision_events(table([row(0, "e", True, 0, 0)]))) == 0


# ------------------------------------------------------------------ min gap
def test_min_gap():
    rows = [
        row(0, "e", True, 0, 0), row(0, "o", False, 7, 0.5),  # x gap 5-2 = 3
        row(1, "e", True, 0, 0), row(1, "o", False, 4.5, 0),  # o: x in [2.5,6.5] -> gap 2.5-2 = 0.5
        row(2, "e", True, 0, 0), row(2, "o", False, 10, 0),  # gap 6
        row(1, "n1", False, 100, 0), row(1, "n2", False, 101, 0),  # non-ego pair ignored
    ]
    assert min_gap_m(table(rows)) == pytest.approx(0.5)
    assert min_gap_m(table([row(0, "e", True, 0, 0), row(1, "e", True, 1, 0)])) is None
    assert min_gap_m(table([row(0, "e", True, 0, 0), row(0, "f", True, 3, 0)])) == 0.0


# ------------------------------------------------------------------ order parameters
def test_phi_coll_two_egos_one_other():
    rows = [
        # step 0: (E1,E2) d=2 and (E2,E1) d=2 close; (E1,O)=10, (E2,O)=8 not -> 2/(2*2) = 0.5
        row(0, "E1", True, 0, 0), row(0, "E2", True, 2, 0), row(0, "O", False, 10, 0),
        # step 1: only (E1,O) d=1 close ((E2,E1)=5, (E2,O)=hypot(5,1)) -> 1/4 = 0.25
        row(1, "E1", True, 0, 0), row(1, "E2", True, 5, 0), row(1, "O", False, 0, 1),
        # step 2: (E1,E2) d=3 is NOT < 3; (E1,O) 2.9 close; (E2,O) 5.9 -> 1/4 = 0.25
        row(2, "E1", True, 0, 0), row(2, "E2", True, 0, 3), row(2, "O", False, 0, -2.9),
        # step 3: E1 alone -> N_ego*(N-1) = 0 -> f = 0 (step still counts)
        row(3, "E1", True, 0, 0),
        # step 4: no ego -> not part of the time average
        row(4, "O", False, 0, 0),
    ]
    # (0.5 + 0.25 + 0.25 + 0) / 4 = 0.25, independent of dt
    assert phi_coll(table(rows), DT) == pytest.approx(0.25)
    assert phi_coll(table(rows), 0.1) == pytest.approx(0.25)


def test_phi_coll_all_egos_is_eq12():
    # N=3 egos, one step: A-B d=1 close (both orders: 2), C 10 away; N(N-1) = 6 -> 1/3
    t = table([row(0, "A", True, 0, 0), row(0, "B", True, 1, 0), row(0, "C", True, 10, 0)])
    assert phi_coll(t, DT) == pytest.approx(1 / 3)
    assert phi_coll(table([row(0, "O", False, 0, 0)]), DT) == 0.0


def test_phi_wall():
    assert phi_wall([]) == 0.0
    assert phi_wall([0.0, 0.0]) == 0.0
    assert phi_wall([0.0, 1.0, 3.0]) == pytest.approx(2.0)  # (1+3)/2


# ------------------------------------------------------------------ braking curve
def test_braking_curve_D():
    a, p = 2.0, 0.5  # a/p = 4 m/s, reached by r p at r = a/p^2 = 8 m
    assert braking_curve_D(-1.0, a, p) == 0.0
    assert braking_curve_D(0.0, a, p) == 0.0
    assert braking_curve_D(4.0, a, p) == pytest.approx(2.0)  # r p = 2 < 4
    # r p = a/p exactly -> sqrt branch: sqrt(2*2*8 - 4^2) = sqrt(16) = 4 = r p (continuous)
    assert braking_curve_D(8.0, a, p) == pytest.approx(4.0)
    # large r: sqrt(2*2*100 - 16) = sqrt(384)
    assert braking_curve_D(100.0, a, p) == pytest.approx(math.sqrt(384.0))
    out = braking_curve_D(np.array([-1.0, 4.0, 8.0, 100.0]), a, p)
    np.testing.assert_allclose(out, [0.0, 2.0, 4.0, math.sqrt(384.0)])


# ------------------------------------------------------------------ transfer functions
def test_transfer_S_F1():
    x0, d = 4.0, 2.0
    assert transfer_S(1.0, x0, d) == 1.0  # x < x0-d
    assert transfer_S(2.0, x0, d) == pytest.approx(1.0)  # 1/2(1-cos(-pi)) = 1
    assert transfer_S(2.5, x0, d) == pytest.approx(0.5 * (1 + math.sqrt(2) / 2))  # cos(-3pi/4)
    assert transfer_S(3.0, x0, d) == pytest.approx(0.5)  # 1/2(1-cos(-pi/2))
    assert transfer_S(4.0, x0, d) == 0.0
    assert transfer_S(5.0, x0, d) == 0.0
    np.testing.assert_allclose(F1(np.array([1.0, 2.0, 3.0, 4.0]), x0, d), [0.0, 0.0, 0.5, 1.0],
                               atol=1e-12)


def test_F2_F3():
    assert F2(0.0, 2.0) == 1.0
    assert F2(2.0, 2.0) == pytest.approx(math.exp(-1.0))  # exp(-4/4)
    assert F3(0.0, 1.0) == 1.0
    assert F3(1.0, 1.0) == pytest.approx(0.25)  # 1/(1+1)^2
    assert F3(3.0, 1.0) == pytest.approx(1 / 16)


def test_fitness_hand_computed():
    m = fitness(v_vel=3.25, v_flock=4.0, phi_coll=0.00003, n_disc=2.0, n_min=1.0,
                phi_wall=2.0, phi_corr=0.9, n_agents=10)
    # v_tol = 1.5; S(3.25, 4, 1.5) = 1/2(1-cos(pi/1.5 * -0.75)) = 1/2(1-cos(-pi/2)) = 0.5
    assert m["mu_speed"] == pytest.approx(0.5)
    assert m["mu_coll"] == pytest.approx(0.25)  # a^2/(2a)^2
    assert m["mu_disc"] == pytest.approx(0.25)  # N/5 = 2: 4/(2+2)^2
    assert m["mu_cluster"] == pytest.approx(0.5)  # 1 - S(1, 2, 2) = 1 - 1/2(1-cos(-pi/2))
    assert m["mu_wall"] == pytest.approx(math.exp(-1.0))  # exp(-4/4)
    assert m["mu_corr"] == pytest.approx(0.9)
    # 0.5*0.25*0.25*0.5*0.9*e^-1 = 0.0140625 e^-1
    assert m["mu"] == pytest.approx(0.0140625 * math.exp(-1.0))
    assert set(m) == {"mu_speed", "mu_coll", "mu_disc", "mu_cluster", "mu_wall", "mu_corr", "mu"}
    bad = fitness(4.0, 4.0, 0.0, 0.0, 2.0, 0.0, -0.2, 10)
    assert bad["mu_corr"] == 0.0 and bad["mu"] == 0.0
    assert bad["mu_speed"] == 1.0 and bad["mu_cluster"] == 1.0 and bad["mu_coll"] == 1.0


# ------------------------------------------------------------------ motion summary
def test_motion_summary_straight_line():
    rows = [row(s, "e", True, s, 0, speed=2.0) for s in range(5)]  # x 0..4 at t 0..2
    rows += [row(s, "f", True, s - 2, 10, speed=1.0) for s in range(2, 5)]  # x 0..2 at t 1..2
    rows += [row(s, "n", False, 50, 50, speed=9.0) for s in range(5)]
    t = table(rows)
    goals = {"e": (4.0, 0.0), "f": (10.0, 10.0)}
    ms = motion_summary(t, goals, goal_tol_m=0.5)
    e, f = ms["per_ego"]["e"], ms["per_ego"]["f"]
    # e reaches (4,0) at t=2.0 (x=3 is 1 m away > 0.5); started at t=0
    assert e == {"goal_reached": True, "time_to_goal_s": pytest.approx(2.0),
                 "path_length_m": pytest.approx(4.0), "mean_speed_mps": pytest.approx(2.0)}
    assert f["goal_reached"] is False and f["time_to_goal_s"] is None
    assert f["path_length_m"] == pytest.approx(2.0) and f["mean_speed_mps"] == pytest.approx(1.0)
    assert ms["goal_reached"] is False and ms["time_to_goal_s"] is None
    assert ms["path_length_m"] == pytest.approx(3.0)  # (4+2)/2
    assert ms["mean_speed_mps"] == pytest.approx(13 / 8)  # (5*2 + 3*1) / 8 ego rows
    assert "n" not in ms["per_ego"]
    # f without a goal: excluded from goal aggregates
    ms2 = motion_summary(t, {"e": (4.0, 0.0)}, goal_tol_m=0.5)
    assert ms2["per_ego"]["f"]["goal_reached"] is None
    assert ms2["goal_reached"] is True and ms2["time_to_goal_s"] == pytest.approx(2.0)
    # f's goal reached at t=1.5 (x=1), 0.5 s after its first row at t=1.0; max over egos = 2.0
    ms3 = motion_summary(t, {"e": (4.0, 0.0), "f": (1.0, 10.0)}, goal_tol_m=0.5)
    assert ms3["per_ego"]["f"]["time_to_goal_s"] == pytest.approx(0.5)
    assert ms3["goal_reached"] is True and ms3["time_to_goal_s"] == pytest.approx(2.0)


def test_collisions_against_brute_force():
    # brute force (loops, test only) vs the k-d tree pair search (tests/metrics/test_metrics_pairs.py pins
    # the three pair metrics to the former all-pairs implementation)
    from sumo_avoid.core.geometry import convex_overlap, footprint_corners

    rng = np.random.default_rng(3)
    rows = []
    for s in range(6):
        for k in range(7):
            rows.append(row(s, f"v{k}", k < 3, *rng.uniform(0, 12, 2), heading=rng.uniform(-3, 3)))
    t = table(rows)
    ref_ev = collision_events(t)
    contacts = set()
    for s, g in t.groupby("step"):
        c = footprint_corners(g[["x", "y"]].to_numpy(), g["heading"], g["length"], g["width"])
        ids, ego = g["id"].tolist(), g["is_ego"].tolist()
        for i in range(len(g)):
            for j in range(i + 1, len(g)):
                if (ego[i] or ego[j]) and convex_overlap(c[i], c[j])[0]:
                    contacts.add((s, *sorted((ids[i], ids[j]))))
    first = {c for c in contacts if (c[0] - 1, c[1], c[2]) not in contacts}
    assert set(map(tuple, ref_ev[["step", "a", "b"]].values.tolist())) == first
    assert len(first) > 0
