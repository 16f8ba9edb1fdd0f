"""The flocking arena's geometry (SPEC §1.3): a square with virtual walls, polygon obstacles, the
allowed area and how far a point is outside it, random start positions. Pure numpy/shapely.

Units: metres, seconds, SUMO network coordinates. The arena network (nets/arena.net.xml) is only
a grid of roads under the square so that SUMO's moveToXY (keepRoute=2) has a lane within 62.5 m
of every point to map a vehicle onto; the walls are the square, not the roads.
"""
from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import Polygon


def square(origin, size_m: float) -> np.ndarray:
    """(4,2) CCW corners of the square [x0, x0+size] x [y0, y0+size], m."""
    x0, y0 = float(origin[0]), float(origin[1])
    s = float(size_m)
    return np.array([[x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]])


def allowed_area(walls, obstacles=()):
    """shapely geometry: the walls polygon minus the obstacle polygons."""
    area = Polygon(walls)
    for ob in obstacles:
        area = area.difference(Polygon(ob))
    return area


def outside_distance(points, walls, obstacles=()) -> np.ndarray:
    """(M,2) points -> (M,) how far each is outside the allowed area (outside the walls or inside an
    obstacle), m; 0 inside. This is d_i of φ_wall (SPEC §1.1), for point agents (centres)."""
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
