"""``flocking``: the self-propelled-particle flocking model (SPEC §1, seed 000, Vásárhelyi 2018).

Every control update each ego i gets a desired velocity (SPEC eq. 1-10)

    ṽ_i = v_flock v̂_i + Σ_j v_ij_rep + Σ_j v_ij_frict + Σ_s v_is_wall + Σ_o v_io_obstacle
    v_i_desired = ṽ_i/|ṽ_i| · min(|ṽ_i|, v_max)        speed_rule = "cutoff"   (eq. 10)
                = ṽ_i/|ṽ_i| · v_flock                     speed_rule = "rescale"  (reference sim)

with neighbours j = the other egos within r_c. Everything is vectorised over all egos: the pairs
within r_c come from a dense distance matrix for small flocks and from scipy's cKDTree above
``kdtree_min_agents`` (benchmarks/arena.py measures where it pays).

Walls (shill agents, eq. 7-8): one shill per wall *edge* (nearest point of the edge, velocity
v_shill along the edge's inward normal). The walls are the arena square (set by the runner with
:meth:`FlockingController.set_walls`) or, on a road, the boundary of the net's drivable area.
Obstacles: one shill per obstacle polygon at its nearest boundary point, pointing away from it
(edge normal on a face, radial at a corner). Static obstacles come from ``Observation.obstacles``;
other (non-ego) vehicles are moving obstacles (their footprint rectangle) whose shill velocity is
their own velocity plus v_shill outwards (``vehicles_as_obstacles``). With ``sensor = "radar"``
(seed 000 + SPEC §4): flock members' states come over V2V within r_c (the neighbour terms, with
``delay_s`` and noise), everything else from each ego's own radar returns as assumed boxes; a
return near a member's V2V position is that member (``v2v_gate_m``) and is dropped. Inside a wall's wrong side
or inside an obstacle the distance is 0 (D = 0: full correction, SPEC §1).

Reference-simulator options (SPEC §1.3): the desired velocity is recomputed every
``update_period_s``; neighbours' states can arrive ``delay_s`` late; own and neighbours' positions
and velocities can carry Gaussian noise and/or the reference simulator's drifting GPS error
(``gps_sigma_m2ps2``, :mod:`sumo_avoid.core.noise`). The velocity relaxation itself is the actuator's job
(``ego.actuator = "relaxation"``, :mod:`sumo_avoid.actuation.relaxation`).
"""
from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.control.flocking.road_flock import RoadFlock
from sumo_avoid.control.flocking.terms import (
    FlockingParams,
    combine,
    neighbour_terms,
    polygon_shills,
    shill,
    wall_shills,
)
from sumo_avoid.core.geometry import (
    ccw_polygon,
    footprint_corners,
    pad_polygons,
    ring_walls,
    unit_norm,
)
from sumo_avoid.core.types import EgoTask, Keys, Needs, Observation
from sumo_avoid.sensing.perception import radar_obstacles
from sumo_avoid.sensing.v2v import V2VParams


# ------------------------------------------------------------------------------ controller
class FlockingController(BaseController):
    """Vásárhelyi flocking (SPEC §1): repulsion, alignment, walls and obstacles as shill agents."""

    needs = Needs(goals=False, v2v=True)  # a flock has no goal; members' states come over V2V
    metrics = ("flocking",)  # order parameters and fitness (sumo_avoid.metrics.flock_score)
    stats_keys = Keys(("flocking_updates",))  # what stats() writes

    def __init__(self, params: FlockingParams, ctx=None):
        super().__init__(params, ctx)
        self._area = None
        self._walls = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)))
        # on a road (no [arena] walls) each ego flocks in its route frame, the carriageway's edges
        # its walls (control/flocking/road_flock.py); in the arena and without a road, in the plane
        self.road: RoadFlock | None = None
        if ctx is not None and ctx.walls is not None:
            self.set_walls(ctx.walls)
        elif ctx is not None and ctx.road is not None:
            self.road = RoadFlock(ctx.step_s)
        self._last_update = -np.inf
        self._last: tuple = ((), np.zeros((0, 2)))  # (ego ids, commands) of the last update
        self._obs_key = None
        self._obs_polys = None
        self.updates = 0

    # --- walls ---------------------------------------------------------------------------------
    def _set_area(self, geom) -> None:
        polys = geom.geoms if isinstance(geom, MultiPolygon) else [geom]
        rings = []
        for pg in polys:
            pg = orient(pg, 1.0)
            rings.append(np.asarray(pg.exterior.coords))
            rings.extend(np.asarray(r.coords) for r in pg.interiors)
        self._area = geom
        shapely.prepare(self._area)
        self._walls = ring_walls(rings)

    def set_walls(self, polygon) -> None:
        """The allowed area is this polygon ((k,2) vertices, e.g. the arena square), not the road."""
        self._set_area(Polygon(ccw_polygon(polygon)))

    def outside(self, pos) -> np.ndarray:
        if self._area is None:
            return np.zeros(len(pos), bool)
        return ~shapely.contains_xy(self._area, pos[:, 0], pos[:, 1])

    # --- protocol ------------------------------------------------------------------------------
    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        if self.road is not None:
            self.road.add(task)

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        ids, out = self._last
        if vid in ids:  # its command is forgotten; the others keep theirs
            keep = [k for k, v in enumerate(ids) if v != vid]
            self._last = (tuple(ids[k] for k in keep), out[keep])
        if self.road is not None:
            self.road.remove(vid)

    def stats(self) -> dict:
        return {"flocking_updates": self.updates}

    def v2v_params(self) -> V2VParams:
        """The V2V link this flock talks over (delay, noise, GPS error: [controllers.flocking] keys)."""
        p = self.p
        return V2VParams(p.delay_s, p.pos_noise_m, p.vel_noise_mps, p.gps_sigma_m2ps2, p.gps_lambda_ps,
                         p.update_period_s)

    def _static_polys(self, obstacles):
        key = tuple(id(o) for o in obstacles)
        if key != self._obs_key:
            self._obs_key = key
            self._obs_polys = pad_polygons(obstacles) if obstacles else None
        return self._obs_polys

    def desired(self, own_pos, own_vel, heading, nb_pos, nb_vel, obstacles=(), others=None) -> np.ndarray:
        """Desired velocities (E,2) from sensed states (pure function of its inputs and the walls).

        others: None or (corners (B,4,2), velocities (B,2)[, owner (B,)]) of non-ego vehicles (moving
        obstacles); with ``owner`` (radar) ego k only feels the obstacles with owner == k.
        """
        p = self.p
        e = len(own_pos)
        u, spd = unit_norm(own_vel)
        hd = np.column_stack([np.cos(heading), np.sin(heading)])
        u = np.where((spd > 1e-6)[:, None], u, hd)
        v = p.v_flock_mps * u
        rep, fric = neighbour_terms(own_pos, nb_pos, own_vel, nb_vel, p, use_tree=e >= p.kdtree_min_agents)
        v = v + rep + fric
        a, b, inward = self._walls
        if len(a):
            v = v + wall_shills(own_pos, own_vel, a, b, inward, self.outside(own_pos), p)
        polys = self._static_polys(tuple(obstacles))
        if polys is not None:
            dist, nrm = polygon_shills(own_pos, polys)
            v = v + shill(own_vel, dist, nrm, p)
        if others is not None and len(others[0]):
            dist, nrm = polygon_shills(own_pos, others[0])
            if len(others) > 2:  # per-ego sensing: ego k only feels the obstacles it perceives
                dist = np.where(others[2][None, :] == np.arange(e)[:, None], dist, np.inf)
            v_obj = np.broadcast_to(others[1][None], dist.shape + (2,))
            v = v + shill(own_vel, dist, nrm, p, v_obj)
        return combine(v, p)

    def act(self, obs: Observation) -> np.ndarray:
        snap, p = obs.snapshot, self.p
        due = snap.time_s - self._last_update >= p.update_period_s - 1e-9
        if not due:  # between updates each ego keeps its last command
            ids, (last_ids, last) = tuple(obs.ego_ids), self._last
            if ids == last_ids:
                return np.array(last).reshape(-1, 2)
            row = {v: k for k, v in enumerate(last_ids)}
            if all(v in row for v in ids):
                return np.array([last[row[v]] for v in ids]).reshape(-1, 2)
        rows = obs.ego_rows
        own_pos, own_vel, nb_pos, nb_vel = obs.v2v.states(snap, rows)
        others = None
        if p.vehicles_as_obstacles and obs.detections is not None:  # radar: each ego its own returns
            others = radar_obstacles(obs, nb_pos + nb_vel * p.delay_s, p.v2v_gate_m)
        elif p.vehicles_as_obstacles:
            o = np.flatnonzero(~snap.is_ego)
            if len(o):
                others = (footprint_corners(snap.pos[o], snap.heading[o], snap.length[o], snap.width[o]),
                          snap.vel[o])
        if self.road is not None:
            groups = [] if others is None else [(others[0], others[1], others[2] if len(others) > 2 else None)]
            polys = self._static_polys(tuple(obs.obstacles))
            if polys is not None:
                groups.append((polys, np.zeros((len(polys), 2)), None))
            out = self.road.desired(p, obs.ego_ids, own_pos, own_vel, snap.heading[rows], snap.length[rows],
                                    snap.width[rows], nb_pos, nb_vel, groups)
        else:
            out = self.desired(own_pos, own_vel, snap.heading[rows], nb_pos, nb_vel, obs.obstacles, others)
        self._last = (tuple(obs.ego_ids), out)
        self._last_update = snap.time_s
        self.updates += 1
        return out
