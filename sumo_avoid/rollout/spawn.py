"""Set-up hooks of a run (:class:`sumo_avoid.core.interfaces.SetupHook`): done once after SUMO
started and before the first step -- the scenario's static obstacles drawn as SUMO polygons, the
arena's flock spawned (:mod:`sumo_avoid.road.walls` gives the geometry)."""
from __future__ import annotations

import numpy as np

from sumo_avoid.road.walls import random_positions


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
