"""motion_summary (sorted and grouped on integer id codes) and order._nearest_two (a k-d tree query
cut short by a distance bound) against the former code, kept here as the reference: identical
results (==) on random tables. Exact, not within a tolerance, because both sides do the same
arithmetic with the same routines on the same values in the same order (the same hypot, the same
pandas group sums over the rows sorted alike; the same k-d tree's distance routine, the bound only
prunes which nodes are visited): one implementation on one machine, the determinism contract."""
import json

import numpy as np
import pandas as pd
import pytest
from scipy.spatial import cKDTree

from sumo_avoid.metrics.basic import motion_summary
from sumo_avoid.metrics.order import _nearest_two


def ref_motion_summary(traj, goals, goal_tol_m):
    """The former motion_summary (sort_values and groupby on the id strings)."""
    e = traj[traj["is_ego"].astype(bool)].sort_values(["id", "step"], kind="stable")
    per = {}
    if len(e) == 0:
        return {"per_ego": per, "goal_reached": None, "time_to_goal_s": None,
                "path_length_m": None, "mean_speed_mps": None}
    ids = e["id"].astype(str).to_numpy(dtype=str)
    x, y = e["x"].to_numpy(float), e["y"].to_numpy(float)
    t = e["time_s"].to_numpy(float)
    same = np.r_[False, ids[1:] == ids[:-1]]
    seg = np.where(same, np.hypot(np.diff(x, prepend=x[0]), np.diff(y, prepend=y[0])), 0.0)
    uid, inv = np.unique(ids, return_inverse=True)
    goal_xy = np.array([goals.get(i, (np.nan, np.nan)) for i in uid], float).reshape(-1, 2)
    within = np.hypot(x - goal_xy[:, 0][inv], y - goal_xy[:, 1][inv]) <= goal_tol_m
    df = pd.DataFrame({"id": ids, "t": t, "seg": seg, "speed": e["speed"].to_numpy(float),
                       "t_hit": np.where(within, t, np.nan)})
    g = df.groupby("id", sort=True)
    agg = pd.DataFrame({"t0": g["t"].min(), "path": g["seg"].sum(), "v": g["speed"].mean(),
                        "t_hit": g["t_hit"].min()})
    for vid, row in agg.iterrows():
        has_goal = vid in goals
        reached = bool(np.isfinite(row["t_hit"])) if has_goal else None
        per[vid] = {"goal_reached": reached,
                    "time_to_goal_s": float(row["t_hit"] - row["t0"]) if reached else None,
                    "path_length_m": float(row["path"]), "mean_speed_mps": float(row["v"])}
    with_goal = [v for v in per.values() if v["goal_reached"] is not None]
    all_reached = all(v["goal_reached"] for v in with_goal) if with_goal else None
    return {"per_ego": per, "goal_reached": all_reached,
            "time_to_goal_s": (max(v["time_to_goal_s"] for v in with_goal) if all_reached else None),
            "path_length_m": float(np.mean([v["path_length_m"] for v in per.values()])),
            "mean_speed_mps": float(e["speed"].astype(float).mean())}


def random_traj(seed, n_veh=12, n_steps=40):
    rng = np.random.default_rng(seed)
    ids = [f"e{k}" for k in rng.permutation(30)[:n_veh]]
    ego = rng.random(n_veh) < 0.7
    rows = []
    for st in np.cumsum(rng.integers(1, 3, n_steps)):
        for k in range(n_veh):
            if rng.random() < 0.2:
                continue
            rows.append(dict(step=int(st), time_s=0.1 * st, id=ids[k], is_ego=bool(ego[k]),
                             x=rng.normal(k, 3.0), y=rng.normal(0, 3.0), speed=rng.uniform(0, 20)))
    t = pd.DataFrame(rows)
    goals = {i: tuple(rng.normal(0, 3.0, 2)) for i in ids[::2]} | {"absent": (0.0, 0.0)}
    return t.iloc[rng.permutation(len(t))].reset_index(drop=True), goals


@pytest.mark.parametrize("seed", range(8))
def test_motion_summary_same_as_former(seed):
    t, goals = random_traj(seed)
    for g, tol in ((goals, 2.0), ({}, 1.0), (goals, 100.0)):
        new, ref = motion_summary(t, g, tol), ref_motion_summary(t, g, tol)
        assert json.dumps(new) == json.dumps(ref)  # values, None, and key order (same sums, same order: exact)
    none = t.assign(is_ego=False)
    assert motion_summary(none, goals, 1.0) == ref_motion_summary(none, goals, 1.0)


@pytest.mark.parametrize("seed", range(6))
def test_nearest_two_same_as_plain_query(seed):
    rng = np.random.default_rng(seed)
    n_steps = int(rng.integers(1, 30))
    pts = np.column_stack([rng.uniform(0, 50, (n_steps * 20, 2)), np.repeat(np.arange(n_steps), 20) * 500.0])
    pts[::7, :2] *= 40.0  # a few far from the rest: beyond the sampled bound, searched again
    if seed == 0:
        pts = pts[:1]  # a single row: no second neighbour at all
    tree = cKDTree(pts)
    d0, j0 = tree.query(pts, k=2)
    d1, j1 = _nearest_two(tree, pts)
    assert np.array_equal(d0, d1)  # the tree's own distances, by the same routine: exact
    assert np.array_equal(np.isfinite(d0), np.isfinite(d1))
    ok = np.isfinite(d0[:, 1])
    np.testing.assert_allclose(np.linalg.norm(pts[j1[ok, 1]] - pts[ok], axis=1), d1[ok, 1], rtol=1e-12)
