"""A line a car can drive through turns tighter than its turning circle, kept inside its lanes
where their width allows.

SUMO draws a junction's internal lanes with radii a car cannot drive: netgenerate's random nets
turn right at 2.7-4.7 m where a car's centre needs ~5 m (``actuator.min_turn_radius_m``). A car
that follows the lane centre starts turning when the lane does, turns at its limit and comes out
wide, facing the traffic of the opposite lane. A driver takes such a turn wide *before* it and cuts
in at its apex. This module finds that
line as a lateral offset d(s) from the route's reference path (the SPEC §5 frame: points
x_i = P(s_i) + d_i n(s_i) on a grid of spacing h = 0.5 m), by a linear programme over each tight
stretch (where the path's curvature, smoothed over 3 m, exceeds 1 / (f R_min): a turn, not a kink
of the lane polyline between two edges):

    minimise   W_out sum u_i  +  W_k sum sigma_i  +  sum |d_i| h
    subject to |c_i| <= h_i^2 / (g R_min)                      (the car can drive it: hard)
               |c_i| <= h_i^2 / (f R_min) + sigma_i            (with steering to spare: soft)
               lo_i - u_i <= d_i <= hi_i + u_i                 (inside its lanes: soft)
               d = 0 at both ends of the stretch (two points each: on the path, along it)

c_i = (x_{i-1} - 2 x_i + x_{i+1}) . m_i is the line's second difference across it (m_i its unit
normal) and h_i its half chord x_{i+1} - x_{i-1}: c_i / h_i^2 is the line's curvature at i. m_i and
h_i are taken from the previous solution (sequential linear programmes from d = 0, until d moves
less than ``TOL_M``; they converge from the inside, the last curvature a few % above its bound).
f = ``RADIUS_FACTOR`` 1.25, g = ``HARD_FACTOR`` 1.1 (steering in reserve to correct errors); [lo, hi] the ego's lanes narrowed by its half width and a margin, and by
``max_shift_m``. W_out > W_k: the line leaves the lanes only where a car of radius R_min cannot
turn inside them (a turn too tight for the lane's width), and by the least it must; the soft
radius comes next. Solved with scipy's HiGHS (``scipy.optimize.linprog``), a few hundred variables
per turn, about 20-40 ms per programme, once per ego.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.optimize import linprog

#: Grid spacing of the line, m.
STEP_M = 0.5
#: The line may start moving out this far before a tight stretch (and end this far after it), m.
REACH_M = 25.0
#: The line is planned for this multiple of the car's smallest turning radius: following it, the car
#: keeps steering in reserve to correct its errors (at the radius itself a car that falls behind the
#: line in a tight turn cannot catch up and drifts out).
RADIUS_FACTOR = 1.25
#: ... and never tighter than this multiple (hard): at the radius itself a car that falls behind
#: cannot catch up.
HARD_FACTOR = 1.1
#: Sequential linear programmes: the line's normal and chord length from the previous solution;
#: at most this many, until the line moves less than TOL_M.
ITERATIONS = 8
TOL_M = 0.01
#: The line stays within this fraction of the local radius of curvature inside a bend (beyond the
#: centre of curvature the frame's map (s, d) -> x folds back).
FOLD_FRACTION = 0.6
#: Weights (per metre of the line) of leaving the lanes and of the soft radius's slack, against |d|.
OUTSIDE_WEIGHT = 1e4
SLACK_WEIGHT = 1e2


@dataclass(frozen=True, eq=False)
class DrivableLine:
    """Offset d(s) of the drivable line from the reference path (0 outside the tight stretches)."""

    s: np.ndarray  # (K,) grid arc lengths, m (increasing; empty: the path itself is drivable)
    d: np.ndarray  # (K,) offset, m (left > 0)

    def offset(self, s) -> np.ndarray:
        s = np.atleast_1d(np.asarray(s, float))
        if not len(self.s):
            return np.zeros(len(s))
        return np.interp(s, self.s, self.d, left=0.0, right=0.0)

    def slope(self, s) -> np.ndarray:
        """(N,) dd/ds, piecewise constant between grid nodes."""
        s = np.atleast_1d(np.asarray(s, float))
        if len(self.s) < 2:
            return np.zeros(len(s))
        g = np.diff(self.d) / np.diff(self.s)
        i = np.searchsorted(self.s, s, side="right") - 1
        inside = (i >= 0) & (i < len(g))
        return np.where(inside, g[np.clip(i, 0, len(g) - 1)], 0.0)

    @property
    def max_abs_m(self) -> float:
        return float(np.abs(self.d).max()) if len(self.d) else 0.0


NONE = DrivableLine(np.zeros(0), np.zeros(0))


def tight_stretches(s: np.ndarray, kappa: np.ndarray, kappa_max: float, reach_m: float) -> list[tuple[int, int]]:
    """Index ranges [a, b] of the grid ``s`` around every run of |kappa| > kappa_max, widened by
    ``reach_m`` on each side and merged where they overlap."""
    tight = np.flatnonzero(np.abs(kappa) > kappa_max)
    out: list[tuple[int, int]] = []
    if not len(tight):
        return out
    h = s[1] - s[0]
    pad = int(np.ceil(reach_m / h))
    for i in tight:
        a, b = max(int(i) - pad, 0), min(int(i) + pad, len(s) - 1)
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def _second_difference_rows(P: np.ndarray, N: np.ndarray, d: np.ndarray):
    """For the line x_i = P_i + d_i N_i at the current d: the unit normals of the line at the interior
    points and its half chord lengths (from the neighbours)."""
    x = P + d[:, None] * N
    chord = x[2:] - x[:-2]
    h = 0.5 * np.hypot(chord[:, 0], chord[:, 1])
    nrm = np.column_stack([-chord[:, 1], chord[:, 0]]) / np.maximum(2.0 * h, 1e-12)[:, None]
    return nrm, h


def solve_offset(P: np.ndarray, N: np.ndarray, lo: np.ndarray, hi: np.ndarray, kappa_hard: float,
                 kappa_soft: float, fold=None, iterations: int | None = None) -> np.ndarray:
    """The programme of the module docstring on one stretch: the path's points P (n, 2) and unit
    normals N (n, 2) on an even grid, bounds lo, hi (n,), the hard and soft curvature bounds, 1/m,
    ``fold`` = (lowest, highest) d (n,) each, hard (None: free); returns d (n,), 0 at both ends
    (zeros if the solver fails)."""
    n = len(P)
    if n < 5:
        return np.zeros(n)
    lo = np.minimum(lo, 0.0)  # the path itself is always inside
    hi = np.maximum(hi, 0.0)
    d = np.zeros(n)
    rows = np.repeat(np.arange(n - 2), 3)
    cols = (np.arange(n - 2)[:, None] + np.arange(3)).ravel()
    base = P[:-2] - 2.0 * P[1:-1] + P[2:]
    I, Zn = sparse.eye(n), sparse.csr_matrix((n, n))
    S = sparse.eye(n - 2, n, k=1)  # sigma_i on the interior rows
    Z = sparse.csr_matrix((n - 2, n))
    # variables: d, t >= |d|, sigma >= 0 (soft radius), u >= 0 (outside the lanes)
    lanes = sparse.vstack([sparse.hstack([I, Zn, Zn, -I]), sparse.hstack([-I, Zn, Zn, -I]),   # d - u <= hi, -d - u <= -lo
                           sparse.hstack([I, -I, Zn, Zn]), sparse.hstack([-I, -I, Zn, Zn])])  # |d| <= t
    b_lanes = np.concatenate([hi, -lo, np.zeros(2 * n)])
    f_lo, f_hi = (np.full(n, -np.inf), np.full(n, np.inf)) if fold is None else fold
    ends = [(0.0, 0.0) if i in (0, 1, n - 2, n - 1) else (float(f_lo[i]) if np.isfinite(f_lo[i]) else None,
                                                         float(f_hi[i]) if np.isfinite(f_hi[i]) else None)
            for i in range(n)]
    bounds = ends + [(0.0, None)] * (3 * n)
    for _ in range(ITERATIONS if iterations is None else iterations):
        nrm, h = _second_difference_rows(P, N, d)
        # c_i = (x_{i-1} - 2 x_i + x_{i+1}) . m_i = a_i + sum_j w_ij d_j
        w = np.stack([np.einsum("ij,ij->i", N[:-2], nrm), -2.0 * np.einsum("ij,ij->i", N[1:-1], nrm),
                      np.einsum("ij,ij->i", N[2:], nrm)], axis=1).ravel()
        C = sparse.csr_matrix((w, (rows, cols)), shape=(n - 2, n))
        a = np.einsum("ij,ij->i", base, nrm)
        hard, soft = kappa_hard * h * h, kappa_soft * h * h
        A = sparse.vstack([sparse.hstack([C, Z, Z, Z]), sparse.hstack([-C, Z, Z, Z]),
                           sparse.hstack([C, Z, -S, Z]), sparse.hstack([-C, Z, -S, Z]), lanes]).tocsr()
        b = np.concatenate([hard - a, hard + a, soft - a, soft + a, b_lanes])
        hm = float(np.mean(h))
        c = np.concatenate([np.zeros(n), np.full(n, hm), np.full(n, SLACK_WEIGHT / hm), np.full(n, OUTSIDE_WEIGHT * hm)])
        res = linprog(c, A_ub=A, b_ub=b, bounds=bounds, method="highs")
        if res.status != 0 or res.x is None:
            return np.zeros(n)
        change, d = float(np.abs(res.x[:n] - d).max()), np.asarray(res.x[:n], float)
        if change < TOL_M:
            break
    return d


def drivable_line(frame, corridor, half_width_m: float, turn_radius_m: float, *, margin_m: float = 0.1,
                  max_shift_m: float = 1.5, step_m: float = STEP_M, reach_m: float = REACH_M,
                  curvature_smooth_m: float = 3.0) -> DrivableLine:
    """The drivable line of a :class:`~sumo_avoid.road.frenet.RouteFrame` for a car of half width
    ``half_width_m`` and smallest turning radius ``turn_radius_m`` (<= 0: no limit, no line);
    ``corridor(s) -> (lo, hi)`` the bounds of its lanes in d, m."""
    if not turn_radius_m > 0 or frame.length_m < 4 * step_m:
        return NONE
    kappa_max = 1.0 / (RADIUS_FACTOR * turn_radius_m)  # the soft bound; the hard one 1 / (HARD_FACTOR turn_radius_m)
    s = np.arange(0.0, frame.length_m, step_m)
    kappa = type(frame).from_polyline(frame.vertices, smooth_m=curvature_smooth_m).curvature_at(s)  # to find them
    parts = tight_stretches(s, kappa, kappa_max, reach_m)
    if not parts:
        return NONE
    lo, hi = corridor(s)
    room = half_width_m + margin_m
    lo = np.maximum(np.asarray(lo, float) + room, -max_shift_m)
    hi = np.minimum(np.asarray(hi, float) - room, max_shift_m)
    # never as far inside a bend as its centre of curvature, where the frame folds (hard)
    with np.errstate(divide="ignore"):
        inside = FOLD_FRACTION / np.abs(kappa)
    f_lo, f_hi = np.where(kappa < 0, -inside, -np.inf), np.where(kappa > 0, inside, np.inf)
    d = np.zeros(len(s))
    for a, b in parts:
        seg = s[a:b + 1]
        d[a:b + 1] = solve_offset(frame.to_xy(seg, np.zeros(len(seg))), frame.normal_at(seg), lo[a:b + 1], hi[a:b + 1],
                                  1.0 / (HARD_FACTOR * turn_radius_m), kappa_max, (f_lo[a:b + 1], f_hi[a:b + 1]))
    keep = np.abs(d) > 1e-9
    if not keep.any():
        return NONE
    return DrivableLine(s, d)
