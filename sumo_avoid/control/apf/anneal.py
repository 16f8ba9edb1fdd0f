"""APF-SA's escape search (seed 001, Fig. 2): simulated annealing on the frozen potential field, in the route
frame (s, d), over positions whose road-aligned footprint stays within the ego's lanes."""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.control.road_view import FrenetScene, RoadView
from sumo_avoid.core.geometry import footprint_corners


def outside(view: RoadView, x1, L: float, W: float) -> bool:
    """Does a route-aligned footprint at (s, d) = x1 stick out of the ego's lanes?"""
    c = footprint_corners(x1[None, :], np.zeros(1), np.array([L]), np.array([W]))[0]
    lo, hi = view.corridor(c[:, 0])
    return bool(((c[:, 1] < lo - 1e-9) | (c[:, 1] > hi + 1e-9)).any())


def anneal(driver, rng, p, view: RoadView, sc: FrenetScene, target, room_ahead):
    """Seed Fig. 2 on the frozen field of ``driver`` (:class:`ApfDriver`), in (s, d), with the SA keys of ``p``
    (:class:`ApfSaParams`) and ``room_ahead(sc, at, heading)`` (free length ahead, m); returns the escape point
    or None."""
    x0 = sc.q
    # candidate footprints are aligned with the route (where the car would end up driving),
    # not with its momentary heading, which may point at the kerb after a manoeuvre
    U0 = float(driver.field(sc, x0[None, :], target, heading=0.0).U[0])
    x, Ux, T = x0.copy(), U0, p.sa_t0
    for _ in range(p.sa_max_iter):
        a = rng.uniform(0.0, 2.0 * math.pi)
        x1 = x + p.sa_step_m * np.array([math.cos(a), math.sin(a)])
        if outside(view, x1, sc.length, sc.width):
            T *= p.sa_cooling
            continue
        U1 = float(driver.field(sc, x1[None, :], target, heading=0.0).U[0])
        delta = U1 - Ux
        if delta <= 0.0 or math.exp(-delta / max(T, 1e-12)) > rng.uniform():
            x, Ux = x1, U1
        T *= p.sa_cooling
        if (Ux < U0 and np.hypot(*(x - x0)) >= p.sa_escape_m
                and room_ahead(sc, at=x, heading=0.0) >= p.sa_free_ahead_m):
            return x
    return None
