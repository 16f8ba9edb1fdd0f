"""The route frame's windowed projection of one point, compiled (numba): the per-step cost of
placing an ego on its route (:mod:`sumo_avoid.sumo.placement`) was ~40 numpy calls on arrays of a
few elements, ~0.2 ms per ego and step.

:func:`project_window` is :meth:`~sumo_avoid.road.frenet.RouteFrame.to_frenet` with an ``s_hint``
for one point, written operation for operation like it (the same roots of the same quadratic, the
same candidate order, the smallest |d| first found), so both give the same (s, d) (checked bit for
bit against the numpy version on random frames and points in ``tests/road/test_frenet_compiled.py``).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from sumo_avoid.core.compiled import searchsorted

_T_EPS = 1e-9  # as frenet._T_EPS: a root this far outside [0, 1] still belongs to the segment


@njit(cache=True, error_model="numpy")
def _cross(ux, uy, vx, vy):
    return ux * vy - uy * vx


@njit(cache=True, error_model="numpy")
def project_window(vertices, normals, seg_vec, seg_len, s_vertex, x, y, s_hint, window_m):
    """(s, d) of the point (x, y) projected onto the frame's path with s within s_hint ± window_m,
    the candidate of smallest |d| (the first such in the numpy version's order: per segment its two
    roots); (nan, nan) when there is none in the window. Only for windows within [0, length]: the
    numpy version's extensions past the path's ends (a BLAS dot product) are left to it."""
    last = seg_len.shape[0] - 1
    lo, hi = s_hint - window_m, s_hint + window_m
    i0 = min(max(searchsorted(s_vertex, lo, True) - 1, 0), last)
    i1 = min(max(searchsorted(s_vertex, hi, True) - 1, 0), last)
    best_cost, best_s, best_d = np.inf, np.nan, np.nan
    for w in range(i1 - i0 + 1):
        g = min(i0 + w, last)
        ax, ay = vertices[g, 0], vertices[g, 1]
        ex, ey = seg_vec[g, 0], seg_vec[g, 1]
        nax, nay = normals[g, 0], normals[g, 1]
        nbx, nby = normals[g + 1, 0], normals[g + 1, 1]
        mx, my = nbx - nax, nby - nay
        wx, wy = x - ax, y - ay
        qa = -_cross(ex, ey, mx, my)
        qb = _cross(wx, wy, mx, my) - _cross(ex, ey, nax, nay)
        qc = _cross(wx, wy, nax, nay)
        q = -0.5 * (qb + np.copysign(np.sqrt(qb * qb - 4.0 * qa * qc), qb))
        for k in range(2):
            t = q / qa if k == 0 else qc / q
            if not (np.isfinite(t) and t >= -_T_EPS and t <= 1.0 + _T_EPS):
                continue
            t = min(max(t, 0.0), 1.0)
            vx, vy = (1.0 - t) * nax + t * nbx, (1.0 - t) * nay + t * nby
            nrm = max(math.hypot(vx, vy), 1e-300)
            vx, vy = vx / nrm, vy / nrm
            d = (wx - t * ex) * vx + (wy - t * ey) * vy
            s = s_vertex[g] + t * seg_len[g]
            if s >= lo and s <= hi and not np.isnan(d) and abs(d) < best_cost:
                best_cost, best_s, best_d = abs(d), s, d
    return best_s, best_d
