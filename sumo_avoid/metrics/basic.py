"""Safety and performance metrics computed from a recorded run (pure functions, no SUMO).

The trajectory table ``traj`` is a :class:`pandas.DataFrame` with one row per vehicle per step:

    step (int), time_s (s), id (str), is_ego (bool), x, y (centre, m), vx, vy (m/s),
    speed (m/s), heading (rad, CCW from +x), length, width (m)

Also here: the flocking model's braking curve, transfer functions and fitness (SPEC §1, §1.2),
documented with the seed's equation numbers. Units: metres, seconds, radians.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid.core.curves import braking_curve_D  # SPEC §1 eq. 3 (re-exported)
from sumo_avoid.core.geometry import convex_distance, convex_overlap, footprint_corners
from sumo_avoid.metrics.ego_rows import EgoRows
from sumo_avoid.metrics.pairs import Rows

__all__ = [
    "F1", "F2", "F3", "braking_curve_D", "collision_events", "fitness", "min_gap_m", "motion_summary",
    "phi_coll", "phi_wall", "transfer_S",
]

_EVENT_COLS = ["step", "time_s", "a", "b", "x", "y"]


# ---------------------------------------------------------------------------------------------
# collisions and gaps
# ---------------------------------------------------------------------------------------------
def _half_diag(length, width):
    return 0.5 * np.hypot(length, width)  # m, circumscribed-circle radius of a footprint


def _corners(s: Rows, rows: np.ndarray) -> np.ndarray:
    return footprint_corners(np.c_[s.x[rows], s.y[rows]], s.heading[rows], s.length[rows], s.width[rows])


def collision_events(traj: pd.DataFrame, rows: Rows | None = None) -> pd.DataFrame:
    """Footprint contacts involving at least one ego, one event per pair per contact episode.

    Contact = the oriented rectangles (centre x, y; heading; length x width) overlap or touch
    (:func:`sumo_avoid.core.geometry.convex_overlap`, tolerance 1e-9 m). Pairs: ego vs non-ego and
    ego vs ego; pairs of two non-egos are ignored. Broad phase: a pair is tested only when its
    centre distance <= sum of the half diagonals (circumscribed circles touch); the candidates
    come from a k-d tree search (:mod:`sumo_avoid.metrics.pairs`) within twice the largest half
    diagonal.

    An episode is a run of *consecutive recorded steps* (consecutive in the run's sorted list of
    distinct ``step`` values) with contact; any recorded step without contact (including the
    vehicle being absent) ends it, and the next contact is a new event.

    Returns a DataFrame with columns ``step, time_s, a, b, x, y``: first step/time of the episode,
    ids with ``a < b`` (lexicographic), and the midpoint of the two centres (m) at that step.
    Sorted by step, a, b.
    """
    if len(traj) == 0:
        return pd.DataFrame(columns=_EVENT_COLS)
    s = Rows.of(traj) if rows is None else rows
    hd = _half_diag(s.length, s.width)
    i, j = s.pairs_within(2.0 * float(hd.max()) + 1e-9)
    cd = np.hypot(s.x[i] - s.x[j], s.y[i] - s.y[j])
    near = cd <= hd[i] + hd[j] + 1e-9
    i, j = i[near], j[near]
    if i.size == 0:
        return pd.DataFrame(columns=_EVENT_COLS)
    hit = convex_overlap(_corners(s, i), _corners(s, j))
    i, j = i[hit], j[hit]
    if i.size == 0:
        return pd.DataFrame(columns=_EVENT_COLS)
    o = np.lexsort((s.order_pos[j], s.order_pos[i]))  # pair order: by ego row, then partner
    i, j = i[o], j[o]
    ids_i, ids_j = s.ids[i].astype(str), s.ids[j].astype(str)
    swap = ids_j < ids_i
    a = np.where(swap, ids_j, ids_i)
    b = np.where(swap, ids_i, ids_j)
    c = pd.DataFrame({
        "step": s.step[i], "time_s": s.time_s[i], "a": a, "b": b,
        "x": 0.5 * (s.x[i] + s.x[j]), "y": 0.5 * (s.y[i] + s.y[j]), "_rank": s.rank[i],  # index among recorded steps
    }).sort_values(["a", "b", "_rank"], kind="stable")
    same_pair = (c["a"].to_numpy() == np.roll(c["a"].to_numpy(), 1)) & (
        c["b"].to_numpy() == np.roll(c["b"].to_numpy(), 1))
    cont = same_pair & (c["_rank"].to_numpy() == np.roll(c["_rank"].to_numpy(), 1) + 1)
    cont[0] = False
    ev = c.loc[~cont, _EVENT_COLS].sort_values(["step", "a", "b"], kind="stable")
    return ev.reset_index(drop=True)


def min_gap_m(traj: pd.DataFrame, rows: Rows | None = None) -> float | None:
    """Smallest footprint-to-footprint distance, m, between an ego and any other vehicle (ego or
    not) present at the same step, over the whole run. 0 when footprints touch/overlap.

    Returns None (JSON-friendly) when no ego ever shares a step with another vehicle.
    Exact distances are computed only for pairs whose lower bound (centre distance minus the two
    half diagonals) is below the best upper bound ``ub`` (the smallest centre distance minus the two
    half widths, floored at 0; the footprint contains the disc of radius width/2 about its centre).
    Pairs are searched with a k-d tree (:mod:`sumo_avoid.metrics.pairs`) within a radius r, grown
    until r >= ub + 2 × the largest half diagonal: then every pair whose lower bound is <= ub, and
    the pair that sets ub, are among them, so ub and the result are those of all pairs.
    """
    if len(traj) == 0:
        return None
    s = Rows.of(traj) if rows is None else rows
    hd = _half_diag(s.length, s.width)
    hw = 0.5 * s.width
    hd_max = float(hd.max())
    r = 2.0 * hd_max + 1.0
    while True:
        i, j = s.pairs_within(r)
        cd = np.hypot(s.x[i] - s.x[j], s.y[i] - s.y[j])
        if i.size:
            ub = float(np.maximum(cd - hw[i] - hw[j], 0.0).min())
            need = ub + 2.0 * hd_max
            if need <= r or r >= s.extent_m:
                break
            r = need
        elif r >= s.extent_m:  # every pair of every step searched: no ego ever has company
            return None
        else:
            r = 2.0 * r
    keep = cd - hd[i] - hd[j] <= ub
    i, j = i[keep], j[keep]
    if i.size == 0:
        return ub
    d, _, _ = convex_distance(_corners(s, i), _corners(s, j))
    return min(ub, float(d.min()))


# ---------------------------------------------------------------------------------------------
# order parameters (SPEC §1.1)
# ---------------------------------------------------------------------------------------------
def phi_coll(traj: pd.DataFrame, dt_s: float, r_coll_m: float = 3.0, rows: Rows | None = None) -> float:
    """Collision ratio φ_coll (SPEC §1.1, seed eq. 12) from centre distances.

    At each step t with N_ego(t) >= 1 egos and N(t) vehicles present:

        f(t) = #{ordered (i, j): i ego, j != i present, |r_i - r_j| < r_coll} / (N_ego (N - 1))

    (f = 0 when the denominator is 0), and φ_coll = 1/T ∫ f dt with T = (number of steps with an
    ego) × dt_s; with a constant step dt_s cancels, so this is the mean of f over those steps.
    When every vehicle is an ego, N_ego = N and this is exactly SPEC eq. 12,
    1/(T N (N-1)) ∫ Σ_i Σ_{j≠i} h(r_coll - r_ij) dt. Returns 0.0 if no step has an ego.
    The close pairs come from a k-d tree search (:mod:`sumo_avoid.metrics.pairs`); an ego-ego
    pair counts twice (both orders), an ego/non-ego pair once.
    """
    if dt_s <= 0:
        raise ValueError("dt_s must be > 0")
    if len(traj) == 0:
        return 0.0
    s = Rows.of(traj) if rows is None else rows
    nu = s.uniq.size
    count = np.bincount(s.rank, minlength=nu)
    n_ego = np.bincount(s.rank[s.is_ego], minlength=nu)
    i, j = s.pairs_within(r_coll_m)
    hit = np.hypot(s.x[i] - s.x[j], s.y[i] - s.y[j]) < r_coll_m
    i, j = i[hit], j[hit]
    close = np.bincount(s.rank[i], minlength=nu) + np.bincount(s.rank[i[s.is_ego[j]]], minlength=nu)
    with_ego = n_ego > 0
    if not with_ego.any():
        return 0.0
    den = n_ego * (count - 1)
    f = np.where(den > 0, close / np.where(den > 0, den, 1), 0.0)
    T = with_ego.sum() * dt_s  # s
    return float((f[with_ego] * dt_s).sum() / T)


def phi_wall(d) -> float:
    """Mean outside-distance φ_wall (SPEC §1.1, seed eq. 13), m.

    ``d``: array of outside distances, one per ego-step, m (> 0 only when the vehicle is outside
    the allowed area or inside an obstacle). φ_wall = Σ h(d) d / Σ h(d) (the dt cancels);
    0.0 when nobody is ever outside. NaNs are ignored.
    """
    d = np.asarray(d, float).ravel()
    out = d[d > 0]
    return float(out.sum() / out.size) if out.size else 0.0


# ---------------------------------------------------------------------------------------------
# braking curve, transfer functions and fitness (SPEC §1 eq. 3, §1.2 eq. 15–20)
# ---------------------------------------------------------------------------------------------
def _ret(x):
    x = np.asarray(x, float)
    return float(x) if x.ndim == 0 else x


def transfer_S(x, x0, d):
    """Smooth step S(x, x0, d) (SPEC §1.2, seed eq. 15): 1 for x < x0-d, ½(1 - cos(π/d (x-x0)))
    on [x0-d, x0), 0 for x >= x0. d > 0. Vectorised."""
    x, x0, d = np.broadcast_arrays(*(np.asarray(v, float) for v in (x, x0, d)))
    with np.errstate(divide="ignore", invalid="ignore"):
        mid = 0.5 * (1.0 - np.cos(np.pi / d * (x - x0)))
    return _ret(np.where(x < x0 - d, 1.0, np.where(x < x0, mid, 0.0)))


def F1(phi, phi0, d):
    """F1(φ, φ0, d) = 1 - S(φ, φ0, d) (SPEC §1.2, seed eq. 16): 0 below φ0-d, rises to 1 at φ0."""
    return _ret(1.0 - np.asarray(transfer_S(phi, phi0, d)))


def F2(phi, s):
    """F2(φ, s) = exp(-φ²/s²) (SPEC §1.2, seed eq. 17)."""
    phi = np.asarray(phi, float)
    return _ret(np.exp(-(phi ** 2) / np.asarray(s, float) ** 2))


def F3(phi, a):
    """F3(φ, a) = a² / (φ + a)² (SPEC §1.2, seed eq. 18)."""
    a = np.asarray(a, float)
    return _ret(a ** 2 / (np.asarray(phi, float) + a) ** 2)


V_TOL_FRACTION = 0.375  # v_tol = 0.375 v_flock (1.5 m/s at v_flock = 4 m/s)
A_TOL = 0.00003  # a_tol for μ_coll
R_TOL_M = 2.0  # r_tol for μ_wall, m


def fitness(v_vel, v_flock, phi_coll, n_disc, n_min, phi_wall, phi_corr, n_agents) -> dict:
    """Partial fitnesses and total μ (SPEC §1.2, seed eq. 19–20). Inputs are the order
    parameters of SPEC §1.1 (v_vel, v_flock in m/s; φ_wall in m; N_disc, N_min vehicle counts;
    n_agents = N).

        μ_speed   = F1(v_vel, v_flock, 0.375 v_flock)
        μ_coll    = F3(φ_coll, 0.00003)
        μ_disc    = F3(N_disc, N/5)
        μ_cluster = F1(N_min, N/5, N/5)
        μ_wall    = F2(φ_wall, 2 m)
        μ_corr    = h(φ_corr) φ_corr
        μ         = product of the six
    """
    n5 = n_agents / 5.0
    out = {
        "mu_speed": float(F1(v_vel, v_flock, V_TOL_FRACTION * v_flock)),
        "mu_coll": float(F3(phi_coll, A_TOL)),
        "mu_disc": float(F3(n_disc, n5)),
        "mu_cluster": float(F1(n_min, n5, n5)),
        "mu_wall": float(F2(phi_wall, R_TOL_M)),
        "mu_corr": float(phi_corr) if phi_corr > 0 else 0.0,
    }
    out["mu"] = float(np.prod(list(out.values())))
    return out


# ---------------------------------------------------------------------------------------------
# motion summary
# ---------------------------------------------------------------------------------------------
def motion_summary(traj: pd.DataFrame, goals: dict, goal_tol_m: float, egos: EgoRows | None = None,
                   arrivals: dict | None = None) -> dict:
    """Per-ego and aggregate motion figures.

    Per ego present in ``traj`` (rows with is_ego): ``goal_reached`` (its centre came within
    goal_tol_m, m, of ``goals[id]`` = (x, y) m), ``time_to_goal_s`` (first such time_s minus the
    ego's first time_s; None if never), ``path_length_m`` (sum of centre displacements between
    its consecutive rows, m), ``mean_speed_mps`` (mean of its ``speed`` column). An ego in ``arrivals``
    (id -> time_s: SUMO's driver took it to its route's end, its goal, and SUMO took it out there) reached
    its goal then if its centre never came within goal_tol_m (it arrived on another lane than the goal's).
    Egos without an entry in ``goals`` get goal_reached = time_to_goal_s = None and are left out
    of the goal aggregates; goal entries for ids absent from ``traj`` are ignored.

    Aggregates: goal_reached = all egos with a goal reached it (None if no ego has a goal);
    time_to_goal_s = max over those egos (None if any did not reach / none has a goal);
    path_length_m = mean over egos; mean_speed_mps = mean over all ego rows (None without egos).
    Returns ``{"per_ego": {id: {...}}, **aggregates}``.
    """
    egos = EgoRows.of(traj) if egos is None else egos
    e = egos.table
    per: dict = {}
    if len(e) == 0:
        return {"per_ego": per, "goal_reached": None, "time_to_goal_s": None,
                "path_length_m": None, "mean_speed_mps": None}
    o = egos.by_id()  # sorted by (id, step) as sort_values(["id", "step"], kind="stable") would
    e = e.iloc[o]
    inv, uid = egos.code[o], egos.ids  # code of each row's id (as text), ids sorted
    x, y = e["x"].to_numpy(float), e["y"].to_numpy(float)
    t = e["time_s"].to_numpy(float)
    same = np.r_[False, inv[1:] == inv[:-1]]
    seg = np.where(same, np.hypot(np.diff(x, prepend=x[0]), np.diff(y, prepend=y[0])), 0.0)
    goal_xy = np.array([goals.get(i, (np.nan, np.nan)) for i in uid], float).reshape(-1, 2)
    gx, gy = goal_xy[:, 0], goal_xy[:, 1]  # per distinct ego (loop over egos, not rows), m
    within = np.hypot(x - gx[inv], y - gy[inv]) <= goal_tol_m  # False where no goal (NaN)
    df = pd.DataFrame({"id": inv, "t": t, "seg": seg, "speed": e["speed"].to_numpy(float),
                       "t_hit": np.where(within, t, np.nan)})
    g = df.groupby("id", sort=True)  # on the codes: the groups (and sums) of the ids, in their order
    agg = pd.DataFrame({"t0": g["t"].min(), "path": g["seg"].sum(), "v": g["speed"].mean(),
                        "t_hit": g["t_hit"].min()})
    agg.index = np.asarray(uid)[agg.index.to_numpy()]
    for vid, t_arrived in (arrivals or {}).items():
        if vid in agg.index and not np.isfinite(agg.at[vid, "t_hit"]):
            agg.at[vid, "t_hit"] = t_arrived
    for vid, row in agg.iterrows():  # one iteration per ego (reporting only)
        has_goal = vid in goals
        reached = bool(np.isfinite(row["t_hit"])) if has_goal else None
        per[vid] = {
            "goal_reached": reached,
            "time_to_goal_s": float(row["t_hit"] - row["t0"]) if reached else None,
            "path_length_m": float(row["path"]),
            "mean_speed_mps": float(row["v"]),
        }
    with_goal = [v for v in per.values() if v["goal_reached"] is not None]
    all_reached = all(v["goal_reached"] for v in with_goal) if with_goal else None
    return {
        "per_ego": per,
        "goal_reached": all_reached,
        "time_to_goal_s": (max(v["time_to_goal_s"] for v in with_goal) if all_reached else None),
        "path_length_m": float(np.mean([v["path_length_m"] for v in per.values()])),
        "mean_speed_mps": float(e["speed"].astype(float).mean()),
    }
