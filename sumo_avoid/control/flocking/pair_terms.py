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


@njit(cache=True, error_model="numpy")
def _braking_curve(r, a, p):
    """D(r, a, p) of core.curves.braking_curve_D for one value."""
    lin = r * p
    ap = a / p
    sq = math.sqrt(max(2.0 * a * r - ap * ap, 0.0))
    if r <= 0:
        return 0.0
    return lin if lin < ap else sq


@njit(cache=True, error_model="numpy")
def pair_sums(pos_i, pos_j, vel_i, vel_j, i, j, r, n, r0_rep, p_rep, r0_frict, c_frict, v_frict, a_frict, p_frict):
    """(repulsion (n, 2), friction (n, 2)): the two terms' sums per ego over the pairs (i, j, r)."""
    rep = np.zeros((n, 2))
    fric = np.zeros((n, 2))
    for k in range(i.shape[0]):
        a, b, rk = i[k], j[k], r[k]
        if rk < r0_rep:
            dx, dy = pos_i[a, 0] - pos_j[b, 0], pos_i[a, 1] - pos_j[b, 1]
            nrm = math.hypot(dx, dy)
            if nrm > _EPS:
                m = p_rep * (r0_rep - rk)
                rep[a, 0] += m * (dx / max(nrm, _EPS))
                rep[a, 1] += m * (dy / max(nrm, _EPS))
            else:  # bincount adds the 0 term too: +0.0 leaves the sum's bits (and a -0.0 start becomes +0.0)
                rep[a, 0] += 0.0
                rep[a, 1] += 0.0
        dx, dy = vel_i[a, 0] - vel_j[b, 0], vel_i[a, 1] - vel_j[b, 1]
        vij = math.hypot(dx, dy)
        vmax = max(v_frict, _braking_curve(rk - r0_frict, a_frict, p_frict))
        m = -c_frict * (vij - vmax) if vij > vmax else 0.0
        if vij > _EPS:
            fric[a, 0] += m * (dx / max(vij, _EPS))
            fric[a, 1] += m * (dy / max(vij, _EPS))
        else:
            fric[a, 0] += m * 0.0
            fric[a, 1] += m * 0.0
    return rep, fric
