"""The k-d tree pair search of sumo_avoid.metrics.pairs and the pair metrics built on it
(collision_events, min_gap_m, phi_coll) against the former implementation, which listed every
(ego, other) pair of every step. That implementation is kept here, verbatim but for names, as the
reference: on small random tables the new results must hold the same events (steps, pairs) exactly
and the same numbers within 1e-12 relative -- two implementations, so not bit for bit (a distance
may be taken with the pair the other way round); a wrong pair or a missed contact is off by far more."""
import math

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.core.geometry import convex_distance, convex_overlap, footprint_corners
from sumo_avoid.metrics.basic import collision_events, min_gap_m, phi_coll
from sumo_avoid.metrics.pairs import Rows

_EVENT_COLS = ["step", "time_s", "a", "b", "x", "y"]


# ---------------------------------------------------------------- reference (the former code)
def _sorted_arrays(traj):
    t = traj.sort_values(["step", "id"], kind="stable")
    out = {c: t[c].to_numpy(dtype=float) for c in ("x", "y", "heading", "length", "width", "time_s")}
    out["step"] = t["step"].to_numpy(dtype=np.int64)
    out["id"] = t["id"].astype(str).to_numpy(dtype=str)
    out["is_ego"] = t["is_ego"].to_numpy(dtype=bool)
    return out


def _ego_pairs(step, is_ego, unordered, chunk=7):
    if step.size == 0:
        return
    uniq, start, count = np.unique(step, return_index=True, return_counts=True)
    ego_rows = np.flatnonzero(is_ego)
    if ego_rows.size == 0:
        return
    g = np.searchsorted(uniq, step[ego_rows])
    npart = count[g]
    cum = np.cumsum(npart)
    lo = 0
    while lo < ego_rows.size:
        base = cum[lo - 1] if lo else 0
        hi = max(lo + 1, int(np.searchsorted(cum, base + chunk, side="right")))
        er, c, s0 = ego_rows[lo:hi], npart[lo:hi], start[g[lo:hi]]
        i = np.repeat(er, c)
        off = np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c)
        j = np.repeat(s0, c) + off
        keep = j != i
        if unordered:
            keep &= ~is_ego[j] | (i < j)
        yield i[keep], j[keep]
        lo = hi


def _hd(length, width):
    return 0.5 * np.hypot(length, width)


def _corners(s, i):
    return footprint_corners(np.c_[s["x"][i], s["y"][i]], s["heading"][i], s["length"][i], s["width"][i])


def ref_collision_events(traj):
    if len(traj) == 0:
        return pd.DataFrame(columns=_EVENT_COLS)
    s = _sorted_arrays(traj)
    hd = _hd(s["length"], s["width"])
    hits_i, hits_j = [], []
    for i, j in _ego_pairs(s["step"], s["is_ego"], unordered=True):
        cd = np.hypot(s["x"][i] - s["x"][j], s["y"][i] - s["y"][j])
        near = cd <= hd[i] + hd[j] + 1e-9
        i, j = i[near], j[near]
        if i.size == 0:
            continue
        hit = convex_overlap(_corners(s, i), _corners(s, j))
        hits_i.append(i[hit])
        hits_j.append(j[hit])
    if not hits_i or sum(h.size for h in hits_i) == 0:
        return pd.DataFrame(columns=_EVENT_COLS)
    i, j = np.concatenate(hits_i), np.concatenate(hits_j)
    ids = s["id"]
    swap = ids[j] < ids[i]
    a, b = np.where(swap, ids[j], ids[i]), np.where(swap, ids[i], ids[j])
    rank = np.searchsorted(np.unique(s["step"]), s["step"][i])
    c = pd.DataFrame({"step": s["step"][i], "time_s": s["time_s"][i], "a": a, "b": b,
                      "x": 0.5 * (s["x"][i] + s["x"][j]), "y": 0.5 * (s["y"][i] + s["y"][j]), "_rank": rank,
                      }).sort_values(["a", "b", "_rank"], kind="stable")
    same_pair = (c["a"].to_numpy() == np.roll(c["a"].to_numpy(), 1)) & (
        c["b"].to_numpy() == np.roll(c["b"].to_numpy(), 1))
    cont = same_pair & (c["_rank"].to_numpy() == np.roll(c["_rank"].to_numpy(), 1) + 1)
    cont[0] = False
    return c.loc[~cont, _EVENT_COLS].sort_values(["step", "a", "b"], kind="stable").reset_index(drop=True)


def ref_min_gap_m(traj):
    if len(traj) == 0:
        return None
    s = _sorted_arrays(traj)
    hd = _hd(s["length"], s["width"])
    hw = 0.5 * s["width"]
    cands, ub = [], math.inf
    for i, j in _ego_pairs(s["step"], s["is_ego"], unordered=True):
        if i.size == 0:
            continue
        cd = np.hypot(s["x"][i] - s["x"][j], s["y"][i] - s["y"][j])
        ub = min(ub, float(np.maximum(cd - hw[i] - hw[j], 0.0).min()))
        cands.append((i, j, cd - hd[i] - hd[j]))
    if not cands:
        return None
    best = ub
    for i, j, lb in cands:
        keep = lb <= ub
        i, j = i[keep], j[keep]
        if i.size == 0:
            continue
        d, _, _ = convex_distance(_corners(s, i), _corners(s, j))
        best = min(best, float(d.min()))
    return best


def ref_phi_coll(traj, dt_s, r_coll_m=3.0):
    if len(traj) == 0:
        return 0.0
    s = _sorted_arrays(traj)
    uniq, count = np.unique(s["step"], return_counts=True)
    n_ego = np.bincount(np.searchsorted(uniq, s["step"][s["is_ego"]]), minlength=uniq.size)
    close = np.zeros(uniq.size)
    for i, j in _ego_pairs(s["step"], s["is_ego"], unordered=False):
        hit = np.hypot(s["x"][i] - s["x"][j], s["y"][i] - s["y"][j]) < r_coll_m
        close += np.bincount(np.searchsorted(uniq, s["step"][i][hit]), minlength=uniq.size)
    with_ego = n_ego > 0
    if not with_ego.any():
        return 0.0
    den = n_ego * (count - 1)
    f = np.where(den > 0, close / np.where(den > 0, den, 1), 0.0)
    return float((f[with_ego] * dt_s).sum() / (with_ego.sum() * dt_s))


# ---------------------------------------------------------------- random tables
def random_table(seed, n_steps=12, n_veh=9, side=14.0, p_ego=0.5, p_absent=0.15, offset=0.0):
    """Vehicles of mixed sizes on a small square (many contacts and near misses), some absent at
    some steps, steps numbered with holes, rows shuffled, ids that sort differently as text."""
    rng = np.random.default_rng(seed)
    ids = [f"v{k}" for k in rng.permutation(n_veh * 3)[:n_veh]]
    ego = rng.random(n_veh) < p_ego
    size = rng.choice([(4.0, 1.8), (5.0, 2.0), (12.0, 2.5), (0.9, 0.6)], n_veh)
    steps = np.cumsum(rng.integers(1, 3, n_steps))
    pos = rng.uniform(0, side, (n_veh, 2)) + offset
    rows = []
    for st in steps:
        pos = pos + rng.normal(0, 0.6, pos.shape)
        for k in range(n_veh):
            if rng.random() < p_absent:
                continue
            rows.append(dict(step=int(st), time_s=0.25 * st, id=ids[k], is_ego=bool(ego[k]), x=pos[k, 0],
                             y=pos[k, 1], heading=rng.uniform(-np.pi, np.pi), length=size[k][0], width=size[k][1]))
    t = pd.DataFrame(rows)
    return t.iloc[rng.permutation(len(t))].reset_index(drop=True)


CASES = [dict(seed=s) for s in range(25)] + [
    dict(seed=100, p_ego=1.0), dict(seed=101, p_ego=0.1), dict(seed=102, side=200.0),  # far apart: gap search grows
    dict(seed=103, side=2000.0, n_veh=4), dict(seed=104, offset=1e6), dict(seed=105, n_steps=1, n_veh=2),
    dict(seed=106, p_ego=0.0), dict(seed=107, n_steps=300, n_veh=5, side=30.0),
]


def _same_events(new, ref):
    """Event rows, steps and ids exact; the contact points (x, y, m) within 1e-12 relative."""
    pd.testing.assert_frame_equal(new[["step", "a", "b"]], ref[["step", "a", "b"]], check_exact=True)
    pd.testing.assert_frame_equal(new, ref, check_exact=False, rtol=1e-12, atol=1e-12)


def _same_number(new, ref):
    assert (new is None and ref is None) or new == pytest.approx(ref, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("case", CASES)
def test_same_as_the_former_pair_enumeration(case):
    t = random_table(**case)
    _same_events(collision_events(t), ref_collision_events(t))
    ref = ref_min_gap_m(t)
    _same_number(min_gap_m(t), ref)
    for r in (3.0, 0.5, 20.0):
        _same_number(phi_coll(t, 0.25, r), ref_phi_coll(t, 0.25, r))
    rows = Rows.of(t)  # shared search, as metrics.standard does: same results
    _same_events(collision_events(t, rows=rows), ref_collision_events(t))
    _same_number(min_gap_m(t, rows=rows), ref)
    _same_number(phi_coll(t, 0.25, rows=rows), ref_phi_coll(t, 0.25))


def test_random_cases_exercise_contacts_and_none():
    n_events = sum(len(ref_collision_events(random_table(**c))) for c in CASES)
    assert n_events > 20
    assert ref_min_gap_m(random_table(seed=106, p_ego=0.0)) is None
    # smallest gap > 1 m: min_gap_m must search beyond its first radius (largest diagonal + 1 m)
    assert ref_min_gap_m(random_table(seed=102, side=200.0)) > 1.0
    assert ref_min_gap_m(random_table(seed=103, side=2000.0, n_veh=4)) > 50.0


def brute_pairs(t, radius):
    """Every (ego i, other j) pair of one step within radius, each unordered pair once, i the ego /
    the one first by (step, id): as a set of (row i, row j)."""
    out = set()
    for _, g in t.groupby("step"):
        g = g.sort_values("id", kind="stable")
        for a in range(len(g)):
            for b in range(a + 1, len(g)):
                ra, rb = g.iloc[a], g.iloc[b]
                if not (ra.is_ego or rb.is_ego) or math.hypot(ra.x - rb.x, ra.y - rb.y) > radius:
                    continue
                out.add((g.index[a], g.index[b]) if ra.is_ego else (g.index[b], g.index[a]))
    return out


@pytest.mark.parametrize("seed", range(6))
def test_pairs_within_holds_every_pair_in_radius_oriented(seed):
    t = random_table(seed, side=25.0)
    for radius in (2.0, 7.5, 30.0):
        rows = Rows.of(t)
        i, j = rows.pairs_within(radius)
        got = set(zip(i.tolist(), j.tolist()))
        assert len(got) == len(i)  # each pair once
        want = brute_pairs(t, radius)
        assert want <= got  # a superset: the callers test the exact distance
        assert {(b, a) for a, b in want}.isdisjoint(got)  # oriented as the former enumeration
        steps = t["step"].to_numpy()
        assert (steps[i] == steps[j]).all() and t["is_ego"].to_numpy()[i].all()


def test_pairs_within_hand_example():
    # step 1: e (ego) at 0, f (ego) at 3 m, n (other) at 10 m; step 2: e alone -> pairs (e, f) only at 5 m
    t = pd.DataFrame(dict(step=[1, 1, 1, 2], id=["f", "e", "n", "e"], is_ego=[True, True, False, True],
                          x=[3.0, 0.0, 10.0, 0.0], y=0.0, heading=0.0, length=0.5, width=0.5, time_s=0.0))
    i, j = Rows.of(t).pairs_within(2.0)  # at least min_search_m (diagonal + 1 m): 1.707 m < 3 m
    assert (i.tolist(), j.tolist()) == ([], [])
    i, j = Rows.of(t).pairs_within(5.0)
    assert (i.tolist(), j.tolist()) == ([1], [0])  # e before f (ids sorted), whatever the row order
    i, j = Rows.of(t).pairs_within(10.5)
    assert sorted(zip(i.tolist(), j.tolist())) == [(0, 2), (1, 0), (1, 2)]
