"""Order parameters (SPEC §1.1) and μ (SPEC §1.2) on hand-built tables with hand-computed values,
and the vectorised order_parameters against the former per-step one (kept here as the reference)
on random synthetic runs."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from sumo_avoid.metrics import order
from sumo_avoid.metrics.basic import phi_coll, phi_wall
from sumo_avoid.metrics.order import flocking_metrics, order_parameters
from sumo_avoid.road.walls import outside_distance, square


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


# ---------------------------------------------------------------------------------------------
# the vectorised order_parameters against the former per-step implementation
# ---------------------------------------------------------------------------------------------
def _reference_steps(traj):
    e = traj[traj["is_ego"].astype(bool)].sort_values(["step", "id"], kind="stable")
    step = e["step"].to_numpy(np.int64)
    pos = e[["x", "y"]].to_numpy(float)
    vel = e[["vx", "vy"]].to_numpy(float)
    ids = e["id"].astype(str).to_numpy()
    uniq, start, count = np.unique(step, return_index=True, return_counts=True)
    return uniq, start, count, pos, vel, ids


def _reference_clusters(pos, start, count, r_c_m):
    """Rows' cluster labels as the former code found them: one cKDTree per step, all r_c pairs."""
    rows_i, rows_j = [], []
    for s0, c in zip(start, count):
        pr = cKDTree(pos[s0:s0 + c]).query_pairs(r_c_m, output_type="ndarray")
        rows_i.append(pr[:, 0] + s0)
        rows_j.append(pr[:, 1] + s0)
    i, j = np.concatenate(rows_i), np.concatenate(rows_j)
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(len(pos), len(pos)))
    return connected_components(graph, directed=False)


def _reference_order_parameters(traj, r_c_m, r_coll_m=order.R_COLL_M):
    """sumo_avoid.order.order_parameters before vectorisation (commit 44ce2b5), kept as the reference."""
    uniq, start, count, pos, vel, ids = _reference_steps(traj)
    if uniq.size == 0:
        return {"phi_corr": 0.0, "v_vel": 0.0, "n_disc": 0.0, "n_min": 0.0, "mean_nn_dist_m": None, "n_coll": 0}
    speed = np.hypot(vel[:, 0], vel[:, 1])
    unit = np.where((speed > 1e-9)[:, None], vel / np.maximum(speed, 1e-9)[:, None], 0.0)
    close, nn = [], np.full(len(pos), np.nan)
    for s0, c in zip(start, count):  # one iteration per recorded step
        p = pos[s0:s0 + c]
        tree = cKDTree(p)
        if c > 1:
            d, _ = tree.query(p, k=2)
            nn[s0:s0 + c] = d[:, 1]
            cp = tree.query_pairs(r_coll_m, p=2.0, output_type="ndarray")
            cp = cp[np.hypot(*(p[cp[:, 0]] - p[cp[:, 1]]).T) < r_coll_m]  # strictly closer than r_coll
            close.append(np.column_stack([np.full(len(cp), s0), s0 + cp]))
    ncomp, label = _reference_clusters(pos, start, count, r_c_m)
    size = np.bincount(label, minlength=ncomp)[label]  # N_i per row
    usum = np.column_stack([np.bincount(label, unit[:, 0], ncomp), np.bincount(label, unit[:, 1], ncomp)])
    inner = (unit * usum[label]).sum(1) - (unit * unit).sum(1)
    corr_i = np.where(size > 1, inner / np.maximum(size - 1, 1), 0.0)
    step_of_row = np.repeat(np.arange(uniq.size), count)
    per_step = lambda x: np.bincount(step_of_row, x, uniq.size)
    smallest = np.full(uniq.size, np.inf)
    np.minimum.at(smallest, step_of_row, size.astype(float))
    nn_ok = np.isfinite(nn)
    mean_nn = float(np.mean(np.bincount(step_of_row[nn_ok], nn[nn_ok], uniq.size)[count > 1] / count[count > 1])) \
        if nn_ok.any() else None
    return {"phi_corr": float(np.mean(per_step(corr_i) / count)), "v_vel": float(np.mean(per_step(speed) / count)),
            "n_disc": float(np.mean(per_step((size == 1).astype(float)))), "n_min": float(smallest.mean()),
            "mean_nn_dist_m": mean_nn, "n_coll": _reference_episodes(close, start, ids)}


def _reference_episodes(close, start, ids):
    if not close or sum(len(c) for c in close) == 0:
        return 0
    c = np.concatenate(close)
    rank = np.searchsorted(start, c[:, 0])
    a, b = ids[c[:, 1]], ids[c[:, 2]]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    df = pd.DataFrame({"a": lo, "b": hi, "r": rank}).sort_values(["a", "b", "r"], kind="stable")
    same = (df["a"].to_numpy()[1:] == df["a"].to_numpy()[:-1]) & (df["b"].to_numpy()[1:] == df["b"].to_numpy()[:-1])
    cont = same & (np.diff(df["r"].to_numpy()) == 1)
    return int(len(df) - cont.sum())


def _random_run(seed, n=40, steps=60, r_c=80.0):
    """A synthetic recorded table with the recorder's columns and dtypes: several flocks drifting
    in a square (some closer than r_c to each other, some not), vehicles joining and leaving, a
    few stopped, pairs pushed below 3 m for runs of steps (collision episodes), pairs exactly r_c
    apart, non-ego traffic, steps with a single ego or none, rows not in (step, id) order."""
    rng = np.random.default_rng(seed)
    n_flocks = int(rng.integers(1, 5))
    home = rng.uniform(0, 2.5 * r_c, (n_flocks, 2))
    flock = rng.integers(0, n_flocks, n)
    offset = rng.normal(0, rng.uniform(5, 30), (n, 2))
    heading = rng.uniform(-np.pi, np.pi, n_flocks)[flock] + rng.normal(0, 0.3, n)
    first, last = rng.integers(0, steps // 3 + 1, n), rng.integers(2 * steps // 3, steps + 1, n)
    first[rng.random(n) < 0.3] = 0
    rows = []
    for s in range(steps):
        here = np.flatnonzero((first <= s) & (s < last))
        if s % 17 == 5:
            here = here[:1]  # a step with a single ego
        if s % 23 == 11:
            here = here[:0]  # a step with no ego (traffic only)
        drift = np.column_stack([np.cos(heading), np.sin(heading)]) * 4.0 * 0.2 * s
        pos = home[flock] + offset + drift + rng.normal(0, 0.5, (n, 2))
        vel = 4.0 * np.column_stack([np.cos(heading), np.sin(heading)]) + rng.normal(0, 0.3, (n, 2))
        vel[rng.random(n) < 0.05] = 0.0  # stopped
        if n >= 4 and s % 9 < 4:  # vehicle 1 sits 0.5-3.5 m from vehicle 0 on four steps out of nine
            pos[1] = pos[0] + [rng.uniform(0.5, 3.5), 0.0]
        if n >= 4 and s % 13 == 0:  # vehicle 3 exactly r_c (and 3 m) from vehicle 2: both are edges / not close
            pos[3] = pos[2] + rng.choice([[r_c, 0.0], [0.6 * r_c, 0.8 * r_c], [0.0, 3.0]])
        for i in here:
            rows.append((s, f"f{i}", True, *pos[i], *vel[i]))
        for k in range(int(rng.integers(0, 4))):  # other traffic, ignored
            rows.append((s, f"car{k}", False, *rng.uniform(0, 250, 2), 1.0, 0.0))
    df = pd.DataFrame(rows, columns=["step", "id", "is_ego", "x", "y", "vx", "vy"])
    df = df.sample(frac=1.0, random_state=seed).reset_index(drop=True)  # recorder order is not (step, id)
    df["step"] = df["step"].astype(np.int64)
    df["time_s"] = df["step"] * 0.2
    df["speed"] = np.hypot(df["vx"], df["vy"])
    df["heading"] = np.arctan2(df["vy"], df["vx"])
    df["length"], df["width"] = 4.0, 1.8
    return df


def _assert_same(new, ref):
    """Two implementations: counts exact; the float averages within 1e-12 relative, not bit for bit
    (a sum may be grouped differently; a wrong cluster or neighbour moves them by far more)."""
    assert new.keys() == ref.keys()
    for k in ("n_disc", "n_min", "n_coll"):  # time averages of integer counts (sums of integers: exact), the count
        assert new[k] == ref[k], k
    for k in ("phi_corr", "v_vel", "mean_nn_dist_m"):
        if ref[k] is None:
            assert new[k] is None
        else:
            assert new[k] == pytest.approx(ref[k], rel=1e-12, abs=1e-15), k


@pytest.mark.parametrize("seed", range(12))
def test_vectorised_equals_reference_on_random_runs(seed):
    rng = np.random.default_rng(1000 + seed)
    n, steps = int(rng.integers(2, 120)), int(rng.integers(1, 90))
    r_c = float(rng.choice([80.0, 25.0, 150.0]))
    t = _random_run(seed, n, steps, r_c)
    for r in (r_c, 10.0):
        _assert_same(order_parameters(t, r_c_m=r), _reference_order_parameters(t, r_c_m=r))
    m = flocking_metrics(t, v_flock=4.0, r_c_m=r_c, phi_coll=1e-6, phi_wall=0.1)
    assert m["mu"] >= 0.0 and m["n_agents"] == t.loc[t["is_ego"], "id"].nunique()


def test_random_runs_have_what_they_should():
    """The generator really makes collisions, splits, single-ego steps and r_c chains (else the
    comparison above would not exercise them)."""
    t = _random_run(3, 60, 80)
    ref = _reference_order_parameters(t, 80.0)
    assert ref["n_coll"] >= 2 and ref["n_disc"] > 0
    sizes = t[t["is_ego"]].groupby("step").size()
    assert (sizes == 1).any() and sizes.index.size < 80


@pytest.mark.parametrize("seed", range(6))
def test_cluster_partition_equals_per_step_components(seed):
    """_clusters gives the same partition of the rows (labels up to renaming) as one cKDTree and
    connected_components per step, including steps the grid leaves split (chains at 0.95-1 r_c)."""
    rng = np.random.default_rng(seed)
    t = _random_run(seed, int(rng.integers(5, 80)), int(rng.integers(5, 60)))
    chain = pd.DataFrame({"step": 999, "id": [f"c{k}" for k in range(8)], "is_ego": True,
                          "x": np.cumsum(rng.uniform(0.95, 1.0, 8) * 80.0), "y": rng.uniform(0, 1, 8),
                          "vx": 1.0, "vy": 0.0})
    t = pd.concat([t, chain], ignore_index=True)
    uniq, start, count, pos, _, _ = order._steps(t)
    rank = np.repeat(np.arange(uniq.size), count)
    for r_c in (80.0, 30.0, 0.0):
        n_new, new = order._clusters(pos, rank, start, count, r_c)
        n_ref, ref = _reference_clusters(pos, start, count, r_c)
        assert n_new == n_ref
        pairs = set(zip(new.tolist(), ref.tolist()))  # a bijection between labels: same partition
        assert len(pairs) == n_new == n_ref


def test_grid_cannot_be_laid_falls_back_to_pairs():
    # r_c tiny against a 10 km span: no int64 grid key; coincident points are the only r_c edges
    t = _table([(0, "a", 0.0, 0.0, 1.0, 0.0), (0, "b", 0.0, 0.0, 1.0, 0.0), (0, "c", 1e4, 0.0, 1.0, 0.0),
                (1, "a", 0.0, 0.0, 1.0, 0.0), (1, "b", 5.0, 0.0, -1.0, 0.0)])
    for r in (1e-9, 0.0):
        op = order_parameters(t, r_c_m=r)
        _assert_same(op, _reference_order_parameters(t, r_c_m=r))
        assert op["n_disc"] == pytest.approx((1 + 2) / 2) and op["phi_corr"] == pytest.approx((2 / 3 + 0) / 2)
        assert op["n_coll"] == 1


def test_no_ego_and_single_ego():
    t = _table([(0, "a", 0.0, 0.0, 1.0, 0.0)])
    _assert_same(order_parameters(t, 80.0), _reference_order_parameters(t, 80.0))
    assert order_parameters(t, 80.0)["mean_nn_dist_m"] is None
    t2 = _table([(0, "a", 0.0, 0.0, 1.0, 0.0), (1, "b", 1.0, 0.0, 1.0, 0.0)])  # one ego per step: no neighbour
    _assert_same(order_parameters(t2, 80.0), _reference_order_parameters(t2, 80.0))
    assert order_parameters(t2, 80.0)["mean_nn_dist_m"] is None and order_parameters(t2, 80.0)["n_disc"] == 1.0
    t["is_ego"] = False
    assert order_parameters(t, 80.0) == _reference_order_parameters(t, 80.0)  # no ego: the constants of both


def test_nearest_neighbour_hand_values_3_4_5_triangle():
    # a (0,0), b (3,0), c (0,4): b-c 5 m; nearest: a 3, b 3, c 4. Step 1: a alone, d 7 m off a in step 2
    t = _table([(0, "a", 0.0, 0.0, 1.0, 0.0), (0, "b", 3.0, 0.0, 1.0, 0.0), (0, "c", 0.0, 4.0, 1.0, 0.0),
                (1, "a", 0.0, 0.0, 1.0, 0.0),
                (2, "a", 1.0, 1.0, 1.0, 0.0), (2, "d", 1.0, 8.0, 0.0, 1.0)])
    uniq, start, count, pos, _, _ = order._steps(t)
    rank = np.repeat(np.arange(uniq.size), count)
    nn, a, b = order._neighbours(pos, rank, start, count, 3.5)
    np.testing.assert_array_equal(nn, [3.0, 3.0, 4.0, np.nan, 7.0, 7.0])
    assert (a.tolist(), b.tolist()) == ([0], [1])  # a-b 3 m < 3.5 m; a-c 4 m is not
    assert order_parameters(t, r_c_m=80.0)["mean_nn_dist_m"] == (10.0 / 3.0 + 7.0) / 2  # steps with a neighbour


@pytest.mark.parametrize("seed", range(4))
def test_dense_nearest_neighbour_equals_the_tree(seed, monkeypatch):
    """The dense per-step distances (up to _DENSE_MAX egos a step) give the k-d tree's floats within
    2 ULPs (two implementations of dx² + dy², rooted: a compiler may fuse a multiply-add the other
    rounds twice; a wrong neighbour is off by far more) and exactly the same close pairs; steps with
    one ego, none, and varying counts included. Another chunking of the same dense code: bit for bit."""
    rng = np.random.default_rng(50 + seed)
    t = _random_run(seed, int(rng.integers(2, 90)), int(rng.integers(6, 60)))
    uniq, start, count, pos, _, _ = order._steps(t)
    rank = np.repeat(np.arange(uniq.size), count)
    dense = order._neighbours(pos, rank, start, count, 3.0)
    monkeypatch.setattr(order, "_DENSE_MAX", 0)
    tree = order._neighbours(pos, rank, start, count, 3.0)
    np.testing.assert_array_max_ulp(dense[0], tree[0], maxulp=2)  # NaN (alone) only against NaN
    np.testing.assert_array_equal(dense[1], tree[1])
    np.testing.assert_array_equal(dense[2], tree[2])
    monkeypatch.setattr(order, "_DENSE_MAX", 10_000)
    monkeypatch.setattr(order, "_DENSE_CHUNK", 1)  # one step per chunk
    assert order._neighbours(pos, rank, start, count, 3.0)[0].tobytes() == dense[0].tobytes()
