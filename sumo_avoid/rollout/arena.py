"""The flocking arena (SPEC §1.3): a square with virtual walls, polygon obstacles, random starts,
and the reference simulator's vehicle response (velocity relaxation). Pure numpy/shapely.

Units: metres, seconds, SUMO network coordinates. The arena network (nets/arena.net.xml) is only
a grid of roads under the square so that SUMO's moveToXY (keepRoute=2) has a lane within 62.5 m
of every point to map a vehicle onto; the walls are the square, not the roads.
"""
from __future__ import annotations

import numpy as np


def square(origin, size_m: float) -> np.ndarray:
    """(4,2) CCW corners of the square [x0, x0+size] x [y0, y0+size], m."""
    x0, y0 = float(origin[0]), float(origin[1])
    s = float(size_m)
    return np.array([[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]])


def allowed_area(walls, obstacles=()):
    """shapely geometry: the walls polygon minus the obstacle polygons."""
    from shapely.geometry import Polygon

    area = Polygon(walls)
    for ob in obstacles:
        area = area.difference(Polygon(ob))
    return area


def outside_distance(points, walls, obstacles=()) -> np.ndarray:
    """(M,2) points -> (M,) how far each is outside the allowed area (outside the walls or inside an
    obstacle), m; 0 inside. This is d_i of φ_wall (SPEC §1.1), for point agents (centres)."""
    import shapely

    pts = np.asarray(points, float).reshape(-1, 2)
    area = allowed_area(walls, obstacles)
    out = np.zeros(len(pts))
    if len(pts) == 0:
        return out
    inside = shapely.contains_xy(area, pts[:, 0], pts[:, 1])
    if not inside.all():
        k = np.flatnonzero(~inside)
        out[k] = shapely.distance(area.boundary, shapely.points(pts[k]))
    return out


def random_positions(rng: np.random.Generator, n: int, walls, obstacles=(), *, min_spacing_m: float,
                     margin_m: float, max_tries: int = 200_000) -> np.ndarray:
    """n points uniformly at random in the allowed area shrunk by ``margin_m``, pairwise at least
    ``min_spacing_m`` apart (sequential rejection sampling; deterministic for a seeded rng).
    Raises ValueError if they do not fit."""
    import shapely

    area = allowed_area(walls, obstacles).buffer(-margin_m)
    if area.is_empty:
        raise ValueError("arena too small for the margin")
    x0, y0, x1, y1 = area.bounds
    out = np.zeros((n, 2))
    k, tries = 0, 0
    while k < n:
        batch = rng.uniform((x0, y0), (x1, y1), size=(256, 2))
        batch = batch[shapely.contains_xy(area, batch[:, 0], batch[:, 1])]
        for c in batch:  # loop over candidates (placement only, once per run)
            tries += 1
            if k == 0 or np.hypot(*(out[:k] - c).T).min() >= min_spacing_m:
                out[k] = c
                k += 1
                if k == n:
                    break
        if tries > max_tries:
            raise ValueError(f"could not place {n} vehicles {min_spacing_m} m apart (placed {k})")
    return out


def relax(vel, v_des, tau_s: float, max_accel_mps2: float, dt_s: float):
    """Reference-simulator vehicle response: dv/dt = (v_des - v)/τ with |dv/dt| <= a_max.

    vel, v_des (E,2) m/s. Returns (new velocity (E,2), acceleration used (E,2)); the caller moves
    the vehicle by new_velocity·dt (semi-implicit Euler).
    """
    vel = np.asarray(vel, float).reshape(-1, 2)
    acc = (np.asarray(v_des, float).reshape(-1, 2) - vel) / tau_s
    a = np.hypot(acc[:, 0], acc[:, 1])
    scale = np.where(a > max_accel_mps2, max_accel_mps2 / np.maximum(a, 1e-12), 1.0)
    acc = acc * scale[:, None]
    return vel + acc * dt_s, acc


def relaxation_step(pos, vel, heading, v_des, tau_s, max_accel_mps2, dt_s, kick=None):
    """One step for every ego: returns (new centre (E,2), new velocity (E,2), heading (E,), speed (E,)).
    The heading follows the velocity; a stopped vehicle keeps its heading. ``kick`` (E,2): velocity
    noise added after the relaxation (the reference simulator's outer noise, :mod:`.noise`)."""
    new_vel, _ = relax(vel, v_des, tau_s, max_accel_mps2, dt_s)
    if kick is not None:
        new_vel = new_vel + kick
    speed = np.hypot(new_vel[:, 0], new_vel[:, 1])
    head = np.where(speed > 1e-6, np.arctan2(new_vel[:, 1], new_vel[:, 0]), np.asarray(heading, float))
    return np.asarray(pos, float) + new_vel * dt_s, new_vel, head, speed
