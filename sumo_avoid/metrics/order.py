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

How it is computed, all steps at once (no loop over steps except where a step's flock is split):

* Clusters (:func:`_clusters`): a grid of side r_c/3 over every step. Two egos of one step whose
  cells are equal or 8-neighbours are < 2√2/3 r_c ≈ 0.94 r_c apart, so they are linked in the r_c
  graph; the 8-connected blobs of occupied cells ("groups") therefore each lie inside one cluster.
  A step with a single group is a single cluster (the usual case of a flock). Only for the steps
  with several groups are the r_c pairs listed (the step's own cKDTree) and the groups
  they join merged; one ``connected_components`` over the groups of the whole run gives the
  clusters. The result is the connected components of the r_c graph, exactly.
* Nearest neighbour: every distance of each step (:func:`_nearest_dense`), a few steps at a time,
  while a step has at most ``_DENSE_MAX`` egos (at N = 100 about twice as fast as a k-d tree over
  all rows; from about 200 egos the tree wins); above, one cKDTree of (x, y, step index × gap),
  the gap larger than any distance inside a step, so no neighbour is ever found in another step
  and in-step distances are unchanged (the third coordinate differs by exactly 0). Both compute
  dx² + dy², rooted: the same floats up to a rounding in the last bits (tested within 2 ULPs;
  which one runs depends on the egos per step only, so a run stays bit-identical). Collisions: pairs closer than r_coll can only join egos whose
  nearest neighbour is that close, so only those are searched (a cKDTree of them, stacked so).
* Per-step and per-cluster sums with ``np.bincount`` over the (step, id)-sorted rows, which adds in
  row order whatever the labels: with the same clusters and distances, the floats of the loop over
  steps (tests/metrics/test_order.py keeps one as the reference and compares within 1e-12 relative).
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from sumo_avoid.metrics.basic import fitness
from sumo_avoid.metrics.ego_rows import EgoRows

R_COLL_M = 3.0
_WIDEN = 1.0 + 1e-9  # candidate searches use a slightly larger radius; the exact test comes after
_DENSE_MAX = 160  # egos per step up to which all distances of a step beat the k-d tree (about 2x at 100)
_DENSE_CHUNK = 1 << 16  # distances per chunk of steps


def _steps(traj: pd.DataFrame, egos: EgoRows | None = None):
    """Ego rows sorted by (step, id): steps, each step's first row and row count, positions,
    velocities, and the ids as integer codes (equal codes = equal ids)."""
    egos = EgoRows.of(traj) if egos is None else egos
    e, ids = egos.table, egos.code  # codes in the order of the ids
    o = np.lexsort((ids, e["step"].to_numpy(np.int64)))  # = sort_values(["step", "id"], kind="stable")
    step, ids = e["step"].to_numpy(np.int64)[o], ids[o]
    pos = e[["x", "y"]].to_numpy(float)[o]
    vel = e[["vx", "vy"]].to_numpy(float)[o]
    uniq, start, count = np.unique(step, return_index=True, return_counts=True)
    return uniq, start, count, pos, vel, ids


def _components(n: int, a: np.ndarray, b: np.ndarray) -> tuple[int, np.ndarray]:
    """Connected components of the undirected graph on n nodes with edges (a[k], b[k])."""
    graph = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)


def _grid_groups(pos: np.ndarray, rank: np.ndarray, r_c_m: float):
    """Group label per row (see module doc: 8-connected blobs of grid cells of side r_c/3, per
    step), the number of groups and each group's step index. Every row is its own group when no
    grid can be laid (r_c <= 0, or too many cells for an int64 key)."""
    n, n_steps = len(pos), int(rank[-1]) + 1
    if not r_c_m > 0:
        return np.arange(n), n, rank.copy()
    ij = np.floor((pos - pos.min(0)) / (r_c_m / 3.0)).astype(np.int64) + 1  # >= 1, so ±1 stays >= 0
    w = int(ij.max()) + 2  # cell indices +1 stay < w: no neighbour wraps into another column/step
    if n_steps * float(w) * float(w) > 2.0 ** 62:
        return np.arange(n), n, rank.copy()
    key = (rank * w + ij[:, 0]) * w + ij[:, 1]
    cells, cell_of_row = np.unique(key, return_inverse=True)
    src, dst = [], []
    for dx, dy in ((0, 1), (1, -1), (1, 0), (1, 1)):  # the other 4 neighbours are the same edges
        nb = cells + dx * w + dy
        k = np.minimum(np.searchsorted(cells, nb), len(cells) - 1)
        hit = cells[k] == nb
        src.append(np.flatnonzero(hit))
        dst.append(k[hit])
    n_grp, grp_of_cell = _components(len(cells), np.concatenate(src), np.concatenate(dst))
    step_of_grp = np.empty(n_grp, np.int64)
    step_of_grp[grp_of_cell] = cells // (w * w)
    return grp_of_cell[cell_of_row.ravel()], n_grp, step_of_grp


def _clusters(pos, rank, start, count, r_c_m: float) -> tuple[int, np.ndarray]:
    """Number of clusters and the cluster label of each row: connected components of each step's
    graph with an edge when r_ij <= r_c (cKDTree.query_pairs), labels unique over the run."""
    group, n_grp, step_of_grp = _grid_groups(pos, rank, r_c_m)
    split = np.flatnonzero(np.bincount(step_of_grp, minlength=len(start)) > 1)
    a, b = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for s in split:  # steps whose groups may still be joined by pairs the grid cannot vouch for
        s0 = start[s]
        pr = cKDTree(pos[s0:s0 + count[s]]).query_pairs(r_c_m, output_type="ndarray")
        ga, gb = group[s0 + pr[:, 0]], group[s0 + pr[:, 1]]
        joins = ga != gb
        a.append(ga[joins])
        b.append(gb[joins])
    n_clu, clu_of_grp = _components(n_grp, np.concatenate(a), np.concatenate(b))
    return n_clu, clu_of_grp[group]


def _nearest_two(tree: cKDTree, pts: np.ndarray):
    """``tree.query(pts, k=2)``, about a third faster: first with ``distance_upper_bound`` at twice the
    largest nearest-neighbour distance of a sample of the rows (the search prunes with it), then
    unbounded for the rows it left without a neighbour. Same distances (the tree's own, as the
    unbounded search computes them); a row's index can differ only between neighbours at the same
    distance."""
    sample = pts[:: max(1, len(pts) // 500)]
    ds = tree.query(sample, k=2)[0][:, 1]
    bound = 2.0 * float(ds[np.isfinite(ds)].max()) if np.isfinite(ds).any() else np.inf
    d, j = tree.query(pts, k=2, distance_upper_bound=bound)
    miss = np.flatnonzero(~np.isfinite(d[:, 1]))
    if len(miss):
        d[miss], j[miss] = tree.query(pts[miss], k=2)
    return d, j


def _nearest_dense(pos, rank, start, count) -> np.ndarray:
    """Distance to the nearest other ego of the same step (inf when alone), from every distance of
    the step: the steps padded to the most egos of a step (NaN, which ``fmin`` skips), a few steps at
    a time so that the (steps, N, N) arrays stay in cache. dx² + dy², then the square root of the
    smallest, as the k-d tree sums and roots it (the same floats but for a last-bit rounding)."""
    n_max = int(count.max())
    col = np.arange(len(pos)) - start[rank]
    pad = np.full((len(count), n_max, 2), np.nan)
    pad[rank, col] = pos
    best = np.empty((len(count), n_max))
    diag = np.arange(n_max)
    chunk = max(1, _DENSE_CHUNK // (n_max * n_max))
    for s0 in range(0, len(count), chunk):
        x, y = pad[s0:s0 + chunk, :, 0], pad[s0:s0 + chunk, :, 1]
        d2, dy = x[:, :, None] - x[:, None, :], y[:, :, None] - y[:, None, :]
        d2 *= d2
        dy *= dy
        d2 += dy
        d2[:, diag, diag] = np.inf
        best[s0:s0 + chunk] = np.fmin.reduce(d2, axis=2)
    return np.sqrt(best[rank, col])


def _neighbours(pos, rank, start, count, r_coll_m: float):
    """Distance to the nearest other ego of the same step (NaN when alone) and the row pairs
    (a < b) of one step closer than r_coll (strictly, centre distance)."""
    n = len(pos)
    gap = 2.0 * float(np.ptp(pos[:, 0]) + np.ptp(pos[:, 1])) + 2.0 * r_coll_m + 1.0  # > any in-step distance
    stacked = np.column_stack([pos, rank * gap])
    if count.max() <= _DENSE_MAX:
        nn = _nearest_dense(pos, rank, start, count)
        nn[~np.isfinite(nn)] = np.nan
    else:
        d, j = _nearest_two(cKDTree(stacked, balanced_tree=False, compact_nodes=False), stacked)  # fastest build
        j = np.minimum(j[:, 1], n - 1)  # k=2 with a single row overall gives j = n (missing)
        nn = np.where(np.isfinite(d[:, 1]) & (rank[j] == rank), d[:, 1], np.nan)
    # both ends of a pair closer than r_coll have their nearest neighbour that close
    cand = np.flatnonzero(nn < r_coll_m * _WIDEN)
    pr = cKDTree(stacked[cand]).query_pairs(r_coll_m * _WIDEN, output_type="ndarray") if len(cand) > 1 \
        else np.zeros((0, 2), np.int64)
    a, b = cand[pr[:, 0]], cand[pr[:, 1]]  # gap > r_coll: never two steps
    close = np.hypot(*(pos[a] - pos[b]).T) < r_coll_m  # strictly closer than r_coll
    return nn, a[close], b[close]


def order_parameters(traj: pd.DataFrame, r_c_m: float, r_coll_m: float = R_COLL_M,
                     egos: EgoRows | None = None) -> dict:
    """phi_corr, v_vel, n_disc, n_min, mean_nn_dist_m, n_coll of the egos in ``traj`` (see module doc;
    ``egos``: its :class:`EgoRows`, if already made)."""
    uniq, start, count, pos, vel, ids = _steps(traj, egos)
    if uniq.size == 0:
        return {"phi_corr": 0.0, "v_vel": 0.0, "n_disc": 0.0, "n_min": 0.0, "mean_nn_dist_m": None, "n_coll": 0}
    step_of_row = np.repeat(np.arange(uniq.size), count)
    speed = np.hypot(vel[:, 0], vel[:, 1])
    unit = np.where((speed > 1e-9)[:, None], vel / np.maximum(speed, 1e-9)[:, None], 0.0)
    ncomp, label = _clusters(pos, step_of_row, start, count, r_c_m)  # components never span two steps
    nn, ca, cb = _neighbours(pos, step_of_row, start, count, r_coll_m)
    size = np.bincount(label, minlength=ncomp)[label]  # N_i per row
    usum = np.column_stack([np.bincount(label, unit[:, 0], ncomp), np.bincount(label, unit[:, 1], ncomp)])
    inner = (unit * usum[label]).sum(1) - (unit * unit).sum(1)
    corr_i = np.where(size > 1, inner / np.maximum(size - 1, 1), 0.0)
    per_step = lambda x: np.bincount(step_of_row, x, uniq.size)
    phi_corr = float(np.mean(per_step(corr_i) / count))
    v_vel = float(np.mean(per_step(speed) / count))
    n_disc = float(np.mean(per_step((size == 1).astype(float))))
    n_min = float(np.minimum.reduceat(size.astype(float), start).mean())
    nn_ok = np.isfinite(nn)
    mean_nn = float(np.mean(np.bincount(step_of_row[nn_ok], nn[nn_ok], uniq.size)[count > 1] / count[count > 1])) \
        if nn_ok.any() else None
    return {"phi_corr": phi_corr, "v_vel": v_vel, "n_disc": n_disc, "n_min": n_min,
            "mean_nn_dist_m": mean_nn, "n_coll": _episodes(step_of_row[ca], ids[ca], ids[cb])}


def _episodes(rank: np.ndarray, id_a: np.ndarray, id_b: np.ndarray) -> int:
    """Count (pair, episode) over close pairs given as (step index, id code, id code); an episode
    = a run of consecutive recorded steps of one unordered pair."""
    if len(rank) == 0:
        return 0
    lo, hi = np.minimum(id_a, id_b), np.maximum(id_a, id_b)
    o = np.lexsort((rank, hi, lo))
    lo, hi, r = lo[o], hi[o], rank[o]
    cont = (lo[1:] == lo[:-1]) & (hi[1:] == hi[:-1]) & (np.diff(r) == 1)
    return int(len(r) - cont.sum())


def flocking_metrics(traj: pd.DataFrame, *, v_flock: float, r_c_m: float, phi_coll: float, phi_wall: float,
                     egos: EgoRows | None = None) -> dict:
    """Order parameters plus φ_coll, φ_wall, every partial fitness and μ (SPEC §1.1-1.2).
    N (for μ_disc, μ_cluster) = the number of distinct egos in the run."""
    egos = EgoRows.of(traj) if egos is None else egos
    op = order_parameters(traj, r_c_m, egos=egos)
    n_agents = len(egos.ids)
    fit = fitness(op["v_vel"], v_flock, phi_coll, op["n_disc"], op["n_min"], phi_wall, op["phi_corr"],
                  max(n_agents, 1))
    return {**op, "phi_coll": float(phi_coll), "phi_wall": float(phi_wall), "n_agents": n_agents, **fit}
