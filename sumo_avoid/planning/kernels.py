"""The planner's compiled part (numba): the clearance of every path of a population.

The GA evaluates the clearance of N paths x (n-1) segments against P obstacle points every
generation. Numpy broadcasting over (N, n-1, P, 2) computes every segment against every point;
this loop does the same arithmetic, on the points near each segment only, in a fraction of the time
(tests/planning/test_ga.py checks it against the
numpy formulation). The smoothing operator, a loop over waypoints, is here too. Compiled on first use
and cached on disk (``cache=True``), like the radar's kernel.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from sumo_avoid.core.compiled import searchsorted


@njit(cache=True, error_model="numpy")
def _segment_min(ax, ay, bx, by, pts, best):
    """Smallest squared distance below ``best`` from segment (ax, ay) + t (bx, by) to the points
    (sorted by x: only those within sqrt(best) of the segment's x extent are looked at)."""
    xs = pts[:, 0]
    den = bx * bx + by * by
    reach = np.sqrt(best)
    lo = searchsorted(xs, min(ax, ax + bx) - reach, False)
    hi = searchsorted(xs, max(ax, ax + bx) + reach, True)
    for j in range(lo, hi):
        px, py = pts[j, 0] - ax, pts[j, 1] - ay
        t = 0.0
        if den > 0.0:
            t = min(max((px * bx + py * by) / den, 0.0), 1.0)
        gx, gy = px - t * bx, py - t * by
        best = min(best, gx * gx + gy * gy)
    return best


@njit(cache=True, error_model="numpy")
def clearance(pop, pts):
    """(first (N,), rest (N,)): for each path pop[k] (n, 2), the smallest distance from its first
    segment, and from its other segments (inf if none), to any point of ``pts`` (P, 2), m.

    ``pts`` must be sorted by x: a segment only looks at the points whose x lies within the best
    distance so far of its own x extent (exact: the others are farther)."""
    N, n = pop.shape[0], pop.shape[1]
    first = np.empty(N)
    rest = np.empty(N)
    for k in range(N):
        first[k] = np.sqrt(_segment_min(pop[k, 0, 0], pop[k, 0, 1], pop[k, 1, 0] - pop[k, 0, 0],
                                        pop[k, 1, 1] - pop[k, 0, 1], pts, np.inf))
        best = np.inf
        for i in range(1, n - 1):
            best = _segment_min(pop[k, i, 0], pop[k, i, 1], pop[k, i + 1, 0] - pop[k, i, 0],
                                pop[k, i + 1, 1] - pop[k, i, 1], pts, best)
        rest[k] = np.sqrt(best)
    return first, rest


@njit(cache=True, error_model="numpy")
def shortfall(pop, pts, first_radius, radius):
    """(N,) for each path pop[k] (n, 2): the sum over its segments of how far each falls short of
    its radius (``first_radius`` for the first segment, ``radius`` for the others) from the nearest
    of ``pts`` (sorted by x), m; 0 when every segment keeps its radius. Each segment looks only at
    the points within its radius of its x extent."""
    N, n = pop.shape[0], pop.shape[1]
    out = np.zeros(N)
    for k in range(N):
        total = 0.0
        for i in range(n - 1):
            rad = first_radius if i == 0 else radius
            if rad <= 0.0:
                continue
            best = _segment_min(pop[k, i, 0], pop[k, i, 1], pop[k, i + 1, 0] - pop[k, i, 0],
                                pop[k, i + 1, 1] - pop[k, i, 1], pts, rad * rad)
            total += rad - np.sqrt(best)
        out[k] = total
    return out


@njit(cache=True, error_model="numpy")
def smooth(pop, threshold):
    """The smoothing operator in place, waypoint after waypoint (see :func:`sumo_avoid.planning.ga.smooth`)."""
    for k in range(pop.shape[0]):
        for i in range(1, pop.shape[1] - 1):
            px, py = pop[k, i - 1, 0], pop[k, i - 1, 1]
            cx, cy = pop[k, i, 0], pop[k, i, 1]
            nx, ny = pop[k, i + 1, 0], pop[k, i + 1, 1]
            around = np.hypot(cx - px, cy - py) + np.hypot(nx - cx, ny - cy)
            if around > threshold * np.hypot(nx - px, ny - py):
                pop[k, i, 0] = 0.5 * (px + nx)
                pop[k, i, 1] = 0.5 * (py + ny)
    return pop


def warm() -> None:
    """Compile (or load from the cache) now, with the set-up, not inside the first plan."""
    clearance(np.zeros((1, 2, 2)), np.zeros((1, 2)))
    shortfall(np.zeros((1, 2, 2)), np.zeros((1, 2)), 1.0, 1.0)
    smooth(np.zeros((1, 3, 2)), 1.5)
