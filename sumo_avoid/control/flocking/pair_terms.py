"""The flocking model's pair terms compiled (numba): repulsion (eq. 1-2) and friction (eq. 4-6) summed
over the neighbour pairs in one loop, instead of ~30 numpy calls and two ``bincount`` per step.

Written operation for operation like :func:`~sumo_avoid.control.flocking.terms.repulsion` and
:func:`~sumo_avoid.control.flocking.terms.friction` (unit vectors by ``hypot``, the braking curve
D of :mod:`sumo_avoid.core.curves` with (a/p)² as a product, each ego's sum accumulated in the
pairs' order as ``bincount`` does), so both give the same bits (``tests/control/test_pair_terms.py``).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

_EPS = 1e-12  # as geometry.unit_norm's default: a vector no longer than this has no direction


@njit(cache=True, error_model="numpy", inline="always")
def _braking_curve(r, a, p):
    """D(r, a, p) of core.curves.braking_curve_D for one value."""
    if r <= 0:
        return 0.0
    lin = r * p
    ap = a / p
    return lin if lin < ap else math.sqrt(max(2.0 * a * r - ap * ap, 0.0))


@njit(cache=True, error_model="numpy", inline="always")
def _pair(dx, dy, rk, ux, uy, r0_rep, p_rep, r0_frict, c_frict, v_frict, a_frict, p_frict):
    """One pair's repulsion (positions differ by (dx, dy), distance rk) and friction (velocities differ by
    (ux, uy)), operation for operation as the numpy terms: (rx, ry, fx, fy, what) where ``what`` says which
    to add (1: repulsion, 2: friction; a term not added is 0 and would change no sum). Scalars only: a helper
    that took the sum arrays cost ~5x the whole loop (numba counts references to arrays passed in)."""
    what, rx, ry, fx, fy = 0, 0.0, 0.0, 0.0, 0.0
    if rk < r0_rep:
        what = 1
        nrm = math.hypot(dx, dy)
        if nrm > _EPS:
            m = p_rep * (r0_rep - rk)
            rx, ry = m * (dx / max(nrm, _EPS)), m * (dy / max(nrm, _EPS))
        # else: bincount adds the 0 term too (+0.0 leaves the sum's bits; a -0.0 start becomes +0.0)
    vmax = max(v_frict, _braking_curve(rk - r0_frict, a_frict, p_frict))
    if ux * ux + uy * uy < vmax * vmax * (1.0 - 1e-9):
        return rx, ry, fx, fy, what  # |v_i - v_j| surely <= vmax (hypot is within an ulp): no friction to add
    vij = math.hypot(ux, uy)
    m = -c_frict * (vij - vmax) if vij > vmax else 0.0
    if vij > _EPS:
        fx, fy = m * (ux / max(vij, _EPS)), m * (uy / max(vij, _EPS))
    else:
        fx, fy = m * 0.0, m * 0.0
    return rx, ry, fx, fy, what | 2


@njit(cache=True, error_model="numpy")
def pair_sums(pos_i, pos_j, vel_i, vel_j, i, j, r, n, r0_rep, p_rep, r0_frict, c_frict, v_frict, a_frict, p_frict):
    """(repulsion (n, 2), friction (n, 2)): the two terms' sums per ego over the pairs (i, j, r)."""
    rep = np.zeros((n, 2))
    fric = np.zeros((n, 2))
    for k in range(i.shape[0]):
        a, b, rk = i[k], j[k], r[k]
        rx, ry, fx, fy, what = _pair(pos_i[a, 0] - pos_j[b, 0], pos_i[a, 1] - pos_j[b, 1], rk,
                                     vel_i[a, 0] - vel_j[b, 0], vel_i[a, 1] - vel_j[b, 1],
                                     r0_rep, p_rep, r0_frict, c_frict, v_frict, a_frict, p_frict)
        if what & 1:
            rep[a, 0], rep[a, 1] = rep[a, 0] + rx, rep[a, 1] + ry
        if what & 2:
            fric[a, 0], fric[a, 1] = fric[a, 0] + fx, fric[a, 1] + fy
    return rep, fric


BLOCK = 16  # points per block of the neighbour search (cKDTree's default leaf size)


@njit(cache=True, error_model="numpy")
def _blocks(pts):
    """Bounding boxes (B, 4: x0, y0, x1, y1) of consecutive runs of ``BLOCK`` points."""
    nb = (pts.shape[0] + BLOCK - 1) // BLOCK
    box = np.empty((nb, 4))
    for b in range(nb):
        lo, hi = b * BLOCK, min((b + 1) * BLOCK, pts.shape[0])
        box[b, 0], box[b, 1] = pts[lo, 0], pts[lo, 1]
        box[b, 2], box[b, 3] = pts[lo, 0], pts[lo, 1]
        for k in range(lo + 1, hi):
            box[b, 0], box[b, 1] = min(box[b, 0], pts[k, 0]), min(box[b, 1], pts[k, 1])
            box[b, 2], box[b, 3] = max(box[b, 2], pts[k, 0]), max(box[b, 3], pts[k, 1])
    return box


@njit(cache=True, error_model="numpy")
def tree_pair_sums(pos_i, pos_j, vel_i, vel_j, order_j, r_c, same, r0_rep, p_rep, r0_frict, c_frict, v_frict,
                   a_frict, p_frict):
    """:func:`pair_sums` over the neighbour pairs that ``cKDTree.sparse_distance_matrix`` finds within ``r_c``
    (squared distance dx*dx + dy*dy <= r_c*r_c, r its square root; i != j when ``same``), found here and summed
    in one pass. Each ego's terms are added in the order that search yields them (its neighbours j in the
    order of ``order_j`` = ``cKDTree(pos_j).indices``, the tree's leaf order), so the sums are those of
    ``pair_sums`` on its pairs: the points are taken in that order in blocks of ``BLOCK``, and a block whose
    box lies farther than ``r_c`` from the ego is skipped."""
    n, m = pos_i.shape[0], order_j.shape[0]
    pts = np.empty((m, 2))
    for k in range(m):
        pts[k, 0], pts[k, 1] = pos_j[order_j[k], 0], pos_j[order_j[k], 1]
    box = _blocks(pts)
    ub = r_c * r_c
    rep = np.zeros((n, 2))
    fric = np.zeros((n, 2))
    for a in range(n):
        xa, ya = pos_i[a, 0], pos_i[a, 1]
        for bk in range(box.shape[0]):
            gx = max(box[bk, 0] - xa, 0.0, xa - box[bk, 2])
            gy = max(box[bk, 1] - ya, 0.0, ya - box[bk, 3])
            if gx * gx + gy * gy > ub * (1.0 + 1e-9):  # the box is out of reach (with room for rounding)
                continue
            for k in range(bk * BLOCK, min((bk + 1) * BLOCK, m)):
                b = order_j[k]
                if same and b == a:
                    continue
                dx, dy = xa - pos_j[b, 0], ya - pos_j[b, 1]
                d2 = dx * dx + dy * dy
                if d2 > ub:
                    continue
                rx, ry, fx, fy, what = _pair(dx, dy, math.sqrt(d2), vel_i[a, 0] - vel_j[b, 0],
                                             vel_i[a, 1] - vel_j[b, 1],
                                             r0_rep, p_rep, r0_frict, c_frict, v_frict, a_frict, p_frict)
                if what & 1:  # (the same two additions as pair_sums above)
                    rep[a, 0], rep[a, 1] = rep[a, 0] + rx, rep[a, 1] + ry
                if what & 2:
                    fric[a, 0], fric[a, 1] = fric[a, 0] + fx, fric[a, 1] + fy
    return rep, fric


@njit(cache=True, error_model="numpy")
def wall_shill_sums(pos, vel, seg_a, seg_b, inward, outside, v_shill, r0_shill, a_shill, p_shill, normal_only):
    """The shill term (eq. 7-8) of straight walls, summed per ego (E, 2): :func:`~sumo_avoid.control.
    flocking.terms.segment_shills` then :func:`~sumo_avoid.control.flocking.terms.shill` in one loop,
    operation for operation (each ego's sum starts from +0.0, as numpy's sum over the walls does)."""
    e_n, s_n = pos.shape[0], seg_a.shape[0]
    out = np.zeros((e_n, 2))
    for e in range(e_n):
        for s in range(s_n):
            dx, dy = seg_b[s, 0] - seg_a[s, 0], seg_b[s, 1] - seg_a[s, 1]
            l2 = max(dx * dx + dy * dy, 1e-12)
            t = min(max(((pos[e, 0] - seg_a[s, 0]) * dx + (pos[e, 1] - seg_a[s, 1]) * dy) / l2, 0.0), 1.0)
            ox, oy = pos[e, 0] - (seg_a[s, 0] + t * dx), pos[e, 1] - (seg_a[s, 1] + t * dy)
            dist = math.hypot(ox, oy)
            if outside[e] and ox * inward[s, 0] + oy * inward[s, 1] < 0:
                dist = 0.0
            nx, ny = inward[s, 0], inward[s, 1]
            vx, vy = v_shill * nx - vel[e, 0], v_shill * ny - vel[e, 1]
            if normal_only:
                k = vx * nx + vy * ny
                vx, vy = k * nx, k * ny
            v_is = math.hypot(vx, vy)
            ux, uy = (vx / max(v_is, _EPS), vy / max(v_is, _EPS)) if v_is > _EPS else (0.0, 0.0)
            vmax = _braking_curve(dist - r0_shill, a_shill, p_shill)
            mag = v_is - vmax if v_is > vmax else 0.0
            out[e, 0] += mag * ux
            out[e, 1] += mag * uy
    return out
