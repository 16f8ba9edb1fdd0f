"""The radar's compiled parts (numba): footprints (:func:`boxes`), candidate pairs
(:func:`candidates`, step 1 of :mod:`.radar`) and the occlusion and nearest-visible-point
computation (:func:`scan`).

:func:`scan` implements :mod:`.radar` steps 2-4, one ego at a time, for the candidate targets
:func:`candidates` picked:

1. each candidate's vertex azimuths give its angular interval [lo, hi] (clipped to the field of
   view); targets straddling the rear (span >= pi) or outside the field of view are dropped;
2. a candidate lying wholly in the shadow of ONE nearer candidate is dropped (cheap pre-filter);
3. the remaining interval ends cut the field of view into sectors; the candidate hit first by a
   sector's middle ray owns it; a candidate is seen iff it owns a sector;
4. a seen candidate is measured at the nearest point of its visible part: the minimum of its
   depth at the ends of its sectors (nudged onto them) and at its special angles (vertices, feet of
   the perpendiculars from the sensor) inside its sectors.

The arithmetic is written operation for operation like the numpy formulation it replaced (same
expressions, same order, first minimum on ties), so the detections are those of it and their
values agree within 1e-12 relative (checked on random scenes in tests/sensing/test_radar.py; not bit
for bit across machines: numpy dispatches SIMD kernels by CPU, which round ``hypot`` and ``arctan2``
differently in the last bits). numba is used
because the numpy version spends its time on ~150 array operations over small per-ego arrays (the
radar benchmark's largest own cost); this loop does the same work in a fraction of that. Compiled
on first use and cached on disk (``cache=True``). Reductions and slice copies are plain loops,
sorts and searches the helpers of :mod:`sumo_avoid.core.compiled`: they compile in less than half
the time numba's own versions take, with the same results.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from sumo_avoid.core.compiled import searchsorted, sorted_copy, stable_argsort

_TWO_PI = 2 * np.pi
_PI = np.pi


@njit(cache=True, error_model="numpy")
def wrap(a):
    """Angle to [-pi, pi): (a + pi) mod 2 pi - pi (numpy's remainder semantics)."""
    return (a + _PI) % _TWO_PI - _PI


@njit(cache=True, error_model="numpy")
def depth(rel, K, ang):
    """Distance along the ray from the origin at world angle ``ang`` to the boundary of the convex
    polygon ``rel`` (K, 2) (vertices relative to the ray origin); inf if the ray misses."""
    dx, dy = math.cos(ang), math.sin(ang)
    best = np.inf
    for k in range(K):
        kb = k + 1 if k + 1 < K else 0
        ax, ay = rel[k, 0], rel[k, 1]
        abx, aby = rel[kb, 0] - ax, rel[kb, 1] - ay
        denom = dx * aby - dy * abx
        if abs(denom) > 1e-12:
            s = (ax * aby - ay * abx) / denom
            u = (ax * dy - ay * dx) / denom
            if u >= -1e-9 and u <= 1 + 1e-9 and s >= 0 and s < best:
                best = s
    return best


@njit(cache=True, error_model="numpy")
def scan(spos, hd, svel, polys, tvel, ptr, cand, half, max_range):
    """All egos' visible targets.

    spos (E, 2) sensor positions, hd (E,) boresights (rad), svel (E, 2) ego velocities; polys
    (N, K, 2) target vertices (padded by repeating the last one), tvel (N, 2); the candidates of
    ego e are ``cand[ptr[e]:ptr[e + 1]]`` (target indices, increasing); half = half the field of
    view (rad); max_range (m). Returns (ego, target, range_m, azimuth_rad, radial_speed_mps) of
    the seen targets, ordered by ego, then candidate order.
    """
    E, K = spos.shape[0], polys.shape[1]
    M = cand.shape[0]
    out_e = np.empty(M, np.int64)
    out_n = np.empty(M, np.int64)
    out_r = np.empty(M)
    out_a = np.empty(M)
    out_v = np.empty(M)
    m = 0
    for e in range(E):
        c0 = ptr[e]
        T = ptr[e + 1] - c0
        if T == 0:
            continue
        sx, sy, h = spos[e, 0], spos[e, 1], hd[e]
        rel = np.empty((T, K, 2))
        az = np.empty((T, K))
        lo = np.empty(T)  # angular interval, clipped to the field of view
        hi = np.empty(T)
        ok = np.zeros(T, np.bool_)
        far = np.empty(T)
        near = np.empty(T)
        footx = np.empty((T, K))
        footy = np.empty((T, K))
        for t in range(T):
            n = cand[c0 + t]
            for k in range(K):
                rx, ry = polys[n, k, 0] - sx, polys[n, k, 1] - sy
                rel[t, k, 0], rel[t, k, 1] = rx, ry
                az[t, k] = wrap(math.atan2(ry, rx) - h)
            lo_t, hi_t = az[t, 0], az[t, 0]
            for k in range(1, K):  # (loops, not .min()/.max(): numba compiles array reductions slowly)
                lo_t, hi_t = min(lo_t, az[t, k]), max(hi_t, az[t, k])
            lo[t], hi[t] = max(lo_t, -half), min(hi_t, half)  # clipped to the field of view
            ok[t] = (hi_t - lo_t < _PI) and (lo[t] < hi[t])
            f, nr = -np.inf, np.inf
            for k in range(K):  # farthest vertex; nearest boundary point (feet of perpendiculars)
                kb = k + 1 if k + 1 < K else 0
                rx, ry = rel[t, k, 0], rel[t, k, 1]
                f = max(f, math.sqrt(rx * rx + ry * ry))
                abx, aby = rel[t, kb, 0] - rx, rel[t, kb, 1] - ry
                L2 = abx * abx + aby * aby
                tf = -(rx * abx + ry * aby) / L2 if L2 > 1e-12 else 0.0
                tf = min(max(tf, 0.0), 1.0)
                fx, fy = rx + tf * abx, ry + tf * aby
                footx[t, k], footy[t, k] = fx, fy
                nr = min(nr, math.sqrt(fx * fx + fy * fy))
            far[t], near[t] = f, nr
        # one-shadow pre-filter: j hidden when one ok i covers its interval and is wholly nearer
        keep = np.empty(T, np.bool_)
        for t in range(T):
            keep[t] = ok[t]
        for j in range(T):
            if not ok[j]:
                continue
            for i in range(T):
                if ok[i] and lo[i] <= lo[j] and hi[j] <= hi[i] and far[i] < near[j]:
                    keep[j] = False
                    break
        R = 0
        ridx = np.empty(T, np.int64)
        for t in range(T):
            if keep[t]:
                ridx[R] = t
                R += 1
        if R == 0:
            continue
        # sectors between the sorted interval ends
        cuts = np.empty(2 * R + 1)
        cuts[0] = -half
        for r in range(R):
            t = ridx[r]
            cuts[1 + 2 * r] = min(lo[t], half)  # lo >= -half and hi <= half already
            cuts[2 + 2 * r] = max(hi[t], -half)
        cuts = sorted_copy(cuts)
        S = 2 * R
        owner = np.zeros(S, np.int64)
        has = np.zeros(S, np.bool_)
        nearest = np.empty(R)
        for r in range(R):
            nearest[r] = near[ridx[r]]
        by_near = stable_argsort(nearest)
        for s in range(S):
            ang = 0.5 * (cuts[s] + cuts[s + 1]) + h
            best, bi = np.inf, 0
            for q in range(R):  # nearest first; a ray's depth to a target is >= the target's distance
                r = by_near[q]
                if nearest[r] > best * (1 + 1e-9) + 1e-9:  # (margin: rounding) no farther one can be hit first
                    break
                d = depth(rel[ridx[r]], K, ang)
                if d < best or (d == best and r < bi):  # ties: the first in candidate order
                    best, bi = d, r
            owner[s] = bi
            has[s] = best < np.inf and cuts[s + 1] - cuts[s] > 1e-9
        for r in range(R):
            t = ridx[r]
            seen = False
            best, besta = np.inf, 0.0
            for s in range(S):  # the ends of its sectors, nudged onto them
                if owner[s] == r and has[s]:
                    seen = True
                    a0, a1 = cuts[s], cuts[s + 1]
                    eps = min(1e-7, 0.25 * (a1 - a0))
                    d = depth(rel[t], K, (a0 + eps) + h)
                    if d < best:
                        best, besta = d, a0
                    d = depth(rel[t], K, (a1 - eps) + h)
                    if d < best:
                        best, besta = d, a1
            if not seen:
                continue
            for q in range(2 * K):  # vertices, then feet of the perpendiculars, inside its sectors
                sp = az[t, q] if q < K else wrap(math.atan2(footy[t, q - K], footx[t, q - K]) - h)
                inside = False
                for s in range(S):
                    if owner[s] == r and has[s] and cuts[s] <= sp and sp <= cuts[s + 1]:
                        inside = True
                        break
                if inside:
                    d = depth(rel[t], K, sp + h)
                    if d < best:
                        best, besta = d, sp
            if not best <= max_range:
                continue
            n = cand[c0 + t]
            aw = h + besta
            ux, uy = math.cos(aw), math.sin(aw)
            out_e[m], out_n[m], out_r[m], out_a[m] = e, n, best, besta
            out_v[m] = (tvel[n, 0] - svel[e, 0]) * ux + (tvel[n, 1] - svel[e, 1]) * uy
            m += 1
    return out_e[:m], out_n[:m], out_r[:m], out_a[:m], out_v[:m]


@njit(cache=True, error_model="numpy")
def boxes(pos, cos_h, sin_h, length, width):
    """Vehicles' footprints as :func:`sumo_avoid.core.geometry.footprint_corners` computes them (same
    operations, same order: equal within 1e-12; the cosines and sines come from numpy), plus each one's
    centre (mean of its corners) and circumscribed radius. Returns corners (N, 4, 2), centres
    (N, 2), radii (N,)."""
    N = pos.shape[0]
    corners = np.empty((N, 4, 2))
    centre = np.empty((N, 2))
    radius = np.empty(N)
    for i in range(N):
        hl, hw = 0.5 * length[i], 0.5 * width[i]
        fx, fy = cos_h[i], sin_h[i]
        lx, ly = -fy, fx  # 90 degrees CCW of the heading
        for k in range(4):
            a = hl if k < 2 else -hl  # front, front, rear, rear
            b = -hw if k == 0 or k == 3 else hw  # right, left, left, right
            corners[i, k, 0] = (pos[i, 0] + a * fx) + b * lx
            corners[i, k, 1] = (pos[i, 1] + a * fy) + b * ly
        for d in range(2):
            centre[i, d] = (((corners[i, 0, d] + corners[i, 1, d]) + corners[i, 2, d]) + corners[i, 3, d]) / 4.0
        r2 = 0.0
        for k in range(4):
            dx, dy = corners[i, k, 0] - centre[i, 0], corners[i, k, 1] - centre[i, 1]
            r2 = max(r2, math.sqrt(dx * dx + dy * dy))
        radius[i] = r2
    return corners, centre, radius


@njit(cache=True, error_model="numpy")
def candidates(spos, fwd, centre, radius, rows, max_range, cos_half, sin_half):
    """(ego, target) pairs, sorted by ego then target, whose circumscribed disc meets the range
    disc and the field-of-view wedge (|lateral| cos(half) - forward sin(half) <= radius: the disc
    reaches the wedge's side); never the ego itself (``rows[e]`` is ego e's own target index).

    A sweep along the axis the targets spread most on: targets sorted by that coordinate, each ego
    tests only those within ``max_range`` + the largest radius of it (a superset of the exact test,
    which then runs as written in tests/sensing/radar_reference.py's k-d tree version)."""
    E, N = spos.shape[0], centre.shape[0]
    if E == 0 or N == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    rmax, x0, x1, y0, y1 = radius[0], centre[0, 0], centre[0, 0], centre[0, 1], centre[0, 1]
    for n in range(1, N):  # (loops, not .max()/.min(): numba compiles array reductions slowly)
        rmax = max(rmax, radius[n])
        x0, x1 = min(x0, centre[n, 0]), max(x1, centre[n, 0])
        y0, y1 = min(y0, centre[n, 1]), max(y1, centre[n, 1])
    reach = (max_range + rmax) * (1 + 1e-9) + 1e-6
    ax = 0 if x1 - x0 >= y1 - y0 else 1
    key_all = np.empty(N)
    for n in range(N):
        key_all[n] = centre[n, ax]
    order = stable_argsort(key_all)
    key = np.empty(N)
    for q in range(N):
        key[q] = key_all[order[q]]
    cap = max(64, 8 * E)
    out_e = np.empty(cap, np.int64)
    out_n = np.empty(cap, np.int64)
    buf = np.empty(N, np.int64)
    m = 0
    for e in range(E):
        lo = searchsorted(key, spos[e, ax] - reach, False)
        hi = searchsorted(key, spos[e, ax] + reach, True)
        k = 0
        fx, fy = fwd[e, 0], fwd[e, 1]
        for q in range(lo, hi):
            n = order[q]
            dx, dy = centre[n, 0] - spos[e, 0], centre[n, 1] - spos[e, 1]
            ahead, side = dx * fx + dy * fy, abs(dy * fx - dx * fy)
            r = radius[n]
            if ((dx * dx + dy * dy <= (max_range + r) * (max_range + r)) and ahead >= -r
                    and side * cos_half - ahead * sin_half <= r and n != rows[e]):
                buf[k] = n
                k += 1
        if m + k > cap:
            cap = 2 * (m + k)
            out_e, out_n = _grow(out_e, cap), _grow(out_n, cap)
        srt = sorted_copy(buf[:k])
        for q in range(k):  # (element loops: numba compiles slice assignment slowly)
            out_n[m + q] = srt[q]
            out_e[m + q] = e
        m += k
    return out_e[:m], out_n[:m]


@njit(cache=True)
def _grow(a, cap):
    b = np.empty(cap, a.dtype)
    for i in range(a.shape[0]):
        b[i] = a[i]
    return b


def warm() -> None:
    """Load (or, the first time on a machine, compile) the kernel now: the batch fork server calls
    this once so that its forked runs do not each pay for it."""
    tvel = np.zeros((0, 2))
    tvel.flags.writeable = False  # radar.targets passes the target velocities read-only (one compiled version)
    scan(np.zeros((1, 2)), np.zeros(1), np.zeros((1, 2)), np.zeros((0, 4, 2)), tvel, np.zeros(2, np.int64),
         np.zeros(0, np.int64), 0.5, 100.0)
    one, ro, ro2 = np.zeros((1, 2)), np.zeros((1, 2)), np.ones(1)
    ro.flags.writeable = ro2.flags.writeable = False  # a Snapshot's arrays are read-only
    corners, centre, radius = boxes(ro, np.ones(1), np.zeros(1), ro2, ro2)
    candidates(one, one, centre, radius, np.zeros(1, np.int64), 100.0, 0.5, 0.5)
