"""Order parameters of a flocking run (SPEC §1.1) and its fitness μ (SPEC §1.2, via
:func:`sumo_avoid.metrics.basic.fitness`), computed from the recorded table (pure, no SUMO).

Only the controlled vehicles (``is_ego``) are the flock: N = number of egos at a step. Every
quantity is a time-average over the recorded steps (constant step, so dt cancels):

* ``phi_corr``: 1/N Σ_i 1/(N_i-1) Σ_{j∈J_i} v̂_i·v̂_j; clusters = connected components of the
  graph with an edge when r_ij <= r_c; singletons contribute 0; a stopped vehicle (|v| = 0) has
  no direction and contributes 0 (and adds 0 to the others' sums). Computed without pairs:
  Σ_{j∈J_i} v̂_i·v̂_j = v̂_i·(Σ_{j∈C_i} v̂_j) - |v̂_i|².
* ``v_vel``: mean speed; ``n_disc``: number of egos with no other ego within r_c; ``n_min``: size
  of the smallest cluster; ``mean_nn_dist_m``: mean distance to the nearest other ego;
* ``n_coll``: number of ego pairs that come closer than r_coll (centre distance, 3 m), counted
  once per episode of consecutive recorded steps (the seed's N_coll).

φ_coll and φ_wall are passed in (metrics.phi_coll / metrics.phi_wall, or arena distances).
Neighbour pairs per step come from scipy's cKDTree (Python loops over steps only).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from sumo_avoid.metrics.basic import fitness

R_COLL_M = 3.0


def _steps(traj: pd.DataFrame):
    e = traj[traj["is_ego"].astype(bool)].sort_values(["step", "id"], kind="stable")
    step = e["step"].to_numpy(np.int64)
    pos = e[["x", "y"]].to_numpy(float)
    vel = e[["vx", "vy"]].to_numpy(float)
    ids = e["id"].astype(str).to_numpy()
    uniq, start, count = np.unique(step, return_index=True, return_counts=True)
    return uniq, start, count, pos, vel, ids


def order_parameters(traj: pd.DataFrame, r_c_m: float, r_coll_m: float = R_COLL_M) -> dict:
    """phi_corr, v_vel, n_disc, n_min, mean_nn_dist_m, n_coll of the egos in ``traj`` (see module doc)."""
    uniq, start, count, pos, vel, ids = _steps(traj)
    if uniq.size == 0:
        return {"phi_corr": 0.0, "v_vel": 0.0, "n_disc": 0.0, "n_min": 0.0, "mean_nn_dist_m": None, "n_coll": 0}
    speed = np.hypot(vel[:, 0], vel[:, 1])
    unit = np.where((speed > 1e-9)[:, None], vel / np.maximum(speed, 1e-9)[:, None], 0.0)
    rows_i, rows_j, close, nn = [], [], [], np.full(len(pos), np.nan)
    for s0, c in zip(start, count):  # one iteration per recorded step
        p = pos[s0:s0 + c]
        tree = cKDTree(p)
        pr = tree.query_pairs(r_c_m, output_type="ndarray")
        rows_i.append(pr[:, 0] + s0)
        rows_j.append(pr[:, 1] + s0)
        if c > 1:
            d, _ = tree.query(p, k=2)
            nn[s0:s0 + c] = d[:, 1]
            cp = tree.query_pairs(r_coll_m, p=2.0, output_type="ndarray")
            cp = cp[np.hypot(*(p[cp[:, 0]] - p[cp[:, 1]]).T) < r_coll_m]  # strictly closer than r_coll
            close.append(np.column_stack([np.full(len(cp), s0), s0 + cp]))
    i = np.concatenate(rows_i)
    j = np.concatenate(rows_j)
    n = len(pos)
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    ncomp, label = connected_components(graph, directed=False)  # components never span two steps
    size = np.bincount(label, minlength=ncomp)[label]  # N_i per row
    usum = np.column_stack([np.bincount(label, unit[:, 0], ncomp), np.bincount(label, unit[:, 1], ncomp)])
    inner = (unit * usum[label]).sum(1) - (unit * unit).sum(1)
    corr_i = np.where(size > 1, inner / np.maximum(size - 1, 1), 0.0)
    step_of_row = np.repeat(np.arange(uniq.size), count)
    per_step = lambda x: np.bincount(step_of_row, x, uniq.size)  # noqa: E731
    phi_corr = float(np.mean(per_step(corr_i) / count))
    v_vel = float(np.mean(per_step(speed) / count))
    n_disc = float(np.mean(per_step((size == 1).astype(float))))
    smallest = np.full(uniq.size, np.inf)
    np.minimum.at(smallest, step_of_row, size.astype(float))
    n_min = float(smallest.mean())
    nn_ok = np.isfinite(nn)
    mean_nn = float(np.mean(np.bincount(step_of_row[nn_ok], nn[nn_ok], uniq.size)[count > 1] / count[count > 1])) \
        if nn_ok.any() else None
    return {"phi_corr": phi_corr, "v_vel": v_vel, "n_disc": n_disc, "n_min": n_min,
            "mean_nn_dist_m": mean_nn, "n_coll": _episodes(close, start, ids)}


def _episodes(close: list, start: np.ndarray, ids: np.ndarray) -> int:
    """Count (pair, episode) of rows (step start, row a, row b); an episode = consecutive steps."""
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


def flocking_metrics(traj: pd.DataFrame, *, v_flock: float, r_c_m: float, phi_coll: float, phi_wall: float) -> dict:
    """Order parameters plus φ_coll, φ_wall, every partial fitness and μ (SPEC §1.1-1.2).
    N (for μ_disc, μ_cluster) = the number of distinct egos in the run."""
    op = order_parameters(traj, r_c_m)
    n_agents = int(traj.loc[traj["is_ego"].astype(bool), "id"].nunique())
    fit = fitness(op["v_vel"], v_flock, phi_coll, op["n_disc"], op["n_min"], phi_wall, op["phi_corr"],
                  max(n_agents, 1))
    return {**op, "phi_coll": float(phi_coll), "phi_wall": float(phi_wall), "n_agents": n_agents, **fit}
