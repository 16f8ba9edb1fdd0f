"""Order parameters (SPEC §1.1) and μ (SPEC §1.2) on hand-built tables with hand-computed values."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.rollout.arena import outside_distance, square
from sumo_avoid.metrics.basic import phi_coll, phi_wall
from sumo_avoid.metrics.order import flocking_metrics, order_parameters


def _table(rows):
    """rows: (step, id, x, y, vx, vy)."""
    df = pd.DataFrame(rows, columns=["step", "id", "x", "y", "vx", "vy"])
    df["time_s"] = df["step"] * 0.2
    df["is_ego"] = True
    df["speed"] = np.hypot(df["vx"], df["vy"])
    df["heading"] = np.arctan2(df["vy"], df["vx"])
    df["length"], df["width"] = 4.0, 1.8
    return df


def test_one_step_clusters_singleton_and_correlation():
    # a, b, c chained (a-b 50 m, b-c 70 m, a-c 120 m > r_c): one cluster of 3; d alone (singleton)
    t = _table([
        (0, "a", 0.0, 0.0, 1.0, 0.0),
        (0, "b", 50.0, 0.0, 0.0, 2.0),     # perpendicular to a
        (0, "c", 120.0, 0.0, 3.0, 0.0),    # parallel to a
        (0, "d", 500.0, 500.0, 0.0, -1.0),
    ])
    op = order_parameters(t, r_c_m=80.0)
    # a: (cos(a,b) + cos(a,c))/2 = (0 + 1)/2; b: (0 + 0)/2; c: (1 + 0)/2; d singleton: 0 -> sum 1 / N=4
    assert op["phi_corr"] == pytest.approx(0.25)
    assert op["n_disc"] == 1.0
    assert op["n_min"] == 1.0
    assert op["v_vel"] == pytest.approx((1 + 2 + 3 + 1) / 4)
    # nearest neighbours: a 50, b 50, c 70, d: nearest is c at hypot(380, 500)
    assert op["mean_nn_dist_m"] == pytest.approx((50 + 50 + 70 + math.hypot(380, 500)) / 4)


def test_threshold_exactly_rc_connects_and_time_average():
    t = _table([
        (0, "a", 0.0, 0.0, 1.0, 0.0), (0, "b", 80.0, 0.0, 1.0, 0.0),    # exactly r_c: connected
        (1, "a", 0.0, 0.0, 1.0, 0.0), (1, "b", 80.5, 0.0, -1.0, 0.0),   # beyond: two singletons
    ])
    op = order_parameters(t, r_c_m=80.0)
    assert op["phi_corr"] == pytest.approx((1.0 + 0.0) / 2)
    assert op["n_disc"] == pytest.approx((0 + 2) / 2)
    assert op["n_min"] == pytest.approx((2 + 1) / 2)


def test_stopped_vehicle_has_no_direction():
    t = _table([(0, "a", 0.0, 0.0, 0.0, 0.0), (0, "b", 10.0, 0.0, 1.0, 0.0), (0, "c", 20.0, 0.0, 2.0, 0.0)])
    op = order_parameters(t, r_c_m=80.0)
    # a: 0; b: (0 + 1)/2; c: (0 + 1)/2 -> 1/3
    assert op["phi_corr"] == pytest.approx(1.0 / 3.0)


def test_n_coll_counts_episodes_below_3m():
    rows = []
    gaps = [5.0, 2.9, 2.0, 4.0, 2.5, 3.0]  # two episodes below 3 m (3.0 exactly is not below)
    for s, g in enumerate(gaps):
        rows += [(s, "a", 0.0, 0.0, 1.0, 0.0), (s, "b", g, 0.0, 1.0, 0.0)]
    t = _table(rows)
    assert order_parameters(t, r_c_m=80.0)["n_coll"] == 2
    assert phi_coll(t, 0.2) == pytest.approx(3 / 6)  # 3 of 6 steps have the (ordered) pairs < 3 m


def test_flocking_metrics_mu_hand_values():
    # 5 egos in a line 10 m apart, all moving +x at 3 m/s, 2 steps
    rows = [(s, f"v{k}", 10.0 * k, 0.0, 3.0, 0.0) for s in range(2) for k in range(5)]
    m = flocking_metrics(_table(rows), v_flock=4.0, r_c_m=80.0, phi_coll=1e-5, phi_wall=1.0)
    assert m["phi_corr"] == pytest.approx(1.0)
    assert m["n_disc"] == 0.0 and m["n_min"] == 5.0
    mu_speed = 0.5 * (1 - math.cos(math.pi / 1.5 * (3.0 - 4.0)))  # F1 = 1 - S, x in [x0-d, x0)
    mu_speed = 1 - mu_speed
    assert m["mu_speed"] == pytest.approx(mu_speed)
    assert m["mu_coll"] == pytest.approx(3e-5 ** 2 / (1e-5 + 3e-5) ** 2)  # = 0.5625
    assert m["mu_disc"] == 1.0 and m["mu_cluster"] == 1.0  # N/5 = 1, N_min = 5 >= 1
    assert m["mu_wall"] == pytest.approx(math.exp(-0.25))
    assert m["mu"] == pytest.approx(mu_speed * 0.5625 * math.exp(-0.25))


def test_arena_outside_distance_and_phi_wall_nobody_outside():
    walls = square((0, 0), 250.0)
    obst = [np.array([[100.0, 100.0], [120.0, 100.0], [120.0, 120.0], [100.0, 120.0]])]
    d = outside_distance([[10, 10], [-3, 50], [260, 270], [105, 110]], walls, obst)
    np.testing.assert_allclose(d, [0.0, 3.0, math.hypot(10, 20), 5.0])
    assert phi_wall(outside_distance([[10, 10], [200, 30]], walls, obst)) == 0.0
