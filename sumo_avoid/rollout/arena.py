"""The flocking arena (SPEC §1.3): a square with virtual walls, polygon obstacles, random starts,
and the reference simulator's vehicle response (velocity relaxation). Pure numpy/shapely.

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


class StaticObstacles:
    """Set-up hook: the scenario's static obstacles as SUMO polygons (drawn, not driven into by SUMO)."""

    def __init__(self, configs, polygons):
        self.ids = [o.id for o in configs]
        self.polygons = polygons

    def setup(self, sim) -> None:
        for pid, shape in zip(self.ids, self.polygons):
            sim.add_polygon(pid, shape)


class ArenaSpawn:
    """Set-up hook: the flock placed at random in the arena (own random stream), random headings; or
    at the arena's fixed ``starts`` with one heading."""

    def __init__(self, arena, walls, obstacles, rng: np.random.Generator):
        self.arena, self.walls, self.obstacles, self.rng = arena, walls, obstacles, rng

    def setup(self, sim) -> None:
        a = self.arena
        if a.starts:  # fixed starts (a formation), one heading: no random draws
            start, heading0 = np.asarray(a.starts, float), np.full(a.n_agents, np.radians(a.start_heading_deg))
        else:
            start = random_positions(self.rng, a.n_agents, self.walls, self.obstacles, min_spacing_m=a.min_spacing_m,
                                     margin_m=a.margin_m)
            heading0 = self.rng.uniform(-np.pi, np.pi, a.n_agents)
        sim.add_free_vehicles(a.ids, start, heading0, a.initial_speed_mps, a.length_m, a.width_m)
