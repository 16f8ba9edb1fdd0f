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
(``actuator.mode = "relaxation"``, :mod:`sumo_avoid.rollout.arena`).
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
import shapely
from scipy.spatial import cKDTree
from shapely.geometry import MultiPolygon, Polygon
from shapely.geometry.polygon import orient

from sumo_avoid.core.config import field_doc
from sumo_avoid.core.curves import braking_curve_D as D
from sumo_avoid.core.geometry import (
    ccw_polygon,
    footprint_corners,
    pad_polygons,
    ring_walls,
)
from sumo_avoid.core.types import EgoTask, Needs, Observation
from sumo_avoid.sensing.perception import radar_obstacles
from sumo_avoid.sensing.v2v import V2VParams

# seed Table 3 (GA-optimised values at v_flock = 4 / 6 / 8 m/s). v_max is printed only for
# v_flock = 4 (8 m/s); we keep the same ratio v_max = 2 v_flock for 6 and 8 (assumption).
_TABLE3 = {
    "r0_rep_m": (25.6, 41.1, 52.9), "p_rep_ps": (0.13, 0.07, 0.06), "r0_frict_m": (85.3, 88.5, 86.8),
    "c_frict": (0.05, 0.05, 0.06), "v_frict_mps": (0.63, 0.93, 1.48), "p_frict_ps": (3.20, 5.32, 6.87),
    "a_frict_mps2": (4.16, 9.94, 0.98), "r0_shill_m": (0.3, 0.5, 0.1), "v_shill_mps": (13.6, 19.7, 22.8),
    "p_shill_ps": (3.55, 5.44, 8.12), "a_shill_mps2": (3.02, 3.54, 4.18),
    "v_flock_mps": (4.0, 6.0, 8.0), "v_max_mps": (8.0, 12.0, 16.0),
}
PRESETS = {f"paper_v{v}": {k: vals[n] for k, vals in _TABLE3.items()} for n, v in enumerate((4, 6, 8))}
SPEED_RULES = ("cutoff", "rescale")


@dataclass(frozen=True)
class FlockingParams:
    preset: str = field_doc("", doc="'' or paper_v4 / paper_v6 / paper_v8 (seed Table 3); keys left at "
                                    "their default take the preset's value")
    v_flock_mps: float = field_doc(4.0, doc="flocking (self-propulsion) speed v_flock, m/s")
    v_max_mps: float = field_doc(8.0, doc="speed cut-off v_max of eq. 10, m/s")
    r_c_m: float = field_doc(80.0, doc="communication range r_c, m")
    r0_rep_m: float = field_doc(25.6, doc="repulsion range r0_rep, m")
    p_rep_ps: float = field_doc(0.13, doc="repulsion gain p_rep, 1/s")
    r0_frict_m: float = field_doc(85.3, doc="alignment (friction) stopping-point offset r0_frict, m")
    c_frict: float = field_doc(0.05, doc="alignment coefficient C_frict, 1")
    v_frict_mps: float = field_doc(0.63, doc="velocity-difference slack v_frict, m/s")
    p_frict_ps: float = field_doc(3.20, doc="alignment braking-curve gain p_frict, 1/s")
    a_frict_mps2: float = field_doc(4.16, doc="alignment braking-curve acceleration a_frict, m/s^2")
    r0_shill_m: float = field_doc(0.3, doc="wall/obstacle stopping-point offset r0_shill, m")
    v_shill_mps: float = field_doc(13.6, doc="shill speed v_shill, m/s")
    p_shill_ps: float = field_doc(3.55, doc="shill braking-curve gain p_shill, 1/s")
    a_shill_mps2: float = field_doc(3.02, doc="shill braking-curve acceleration a_shill, m/s^2")
    speed_rule: str = field_doc("cutoff", doc="'cutoff' (eq. 10: min(|v|, v_max)) or 'rescale' (|v| := v_flock)")
    update_period_s: float = field_doc(0.0, doc="desired velocity recomputed every this many s (0 = every step)")
    delay_s: float = field_doc(0.0, doc="neighbours' states arrive this late, s")
    pos_noise_m: float = field_doc(0.0, doc="std of Gaussian noise on sensed positions, m")
    vel_noise_mps: float = field_doc(0.0, doc="std of Gaussian noise on sensed velocities, m/s")
    gps_sigma_m2ps2: float = field_doc(0.0, doc="reference simulator's GPS error (damped random walk per vehicle on "
                                                "sensed own and neighbour states), sigma m^2/s^2 (robotsim: 0.005; "
                                                "0 = off; sumo_avoid/noise.py)")
    gps_lambda_ps: float = field_doc(0.1, doc="GPS error damping lambda, 1/s")
    shill_normal_only: bool = field_doc(False, doc="road adaptation (not SPEC): the shill term sees only the velocity "
                                                   "difference along the wall/obstacle normal (default off = eq. 8)")
    vehicles_as_obstacles: bool = field_doc(True, doc="non-ego vehicles are moving obstacles (shill term)")
    v2v_gate_m: float = field_doc(4.0, doc="sensor = 'radar': a return whose box centre lies this close to a flock "
                                           "member's V2V position (extrapolated by delay_s) is that member "
                                           "and is dropped (its V2V state is used), m")
    kdtree_min_agents: int = field_doc(100, doc="use scipy cKDTree for neighbour pairs from this many egos on")

    def __post_init__(self):
        if self.preset:
            if self.preset not in PRESETS:
                raise ValueError(f"preset must be one of {sorted(PRESETS)}")
            defaults = {f.name: f.default for f in fields(self)}
            for k, v in PRESETS[self.preset].items():
                if getattr(self, k) == defaults[k]:
                    object.__setattr__(self, k, v)
        if self.speed_rule not in SPEED_RULES:
            raise ValueError(f"speed_rule must be one of {list(SPEED_RULES)}")
        for k in ("a_frict_mps2", "p_frict_ps", "a_shill_mps2", "p_shill_ps", "r_c_m"):
            if getattr(self, k) <= 0:
                raise ValueError(f"{k} must be > 0")


def preset(name: str, **overrides) -> FlockingParams:
    """``FlockingParams`` with seed Table 3's values for ``paper_v4`` / ``paper_v6`` / ``paper_v8``."""
    return FlockingParams(**{**PRESETS[name], **overrides})


# ------------------------------------------------------------------------------ vector helpers
def _norm(v):
    return np.hypot(v[..., 0], v[..., 1])


def _unit(v, eps=1e-12):
    n = _norm(v)
    return np.where((n > eps)[..., None], v / np.maximum(n, eps)[..., None], 0.0), n


def _sum_by(idx, vecs, n):
    """Σ of (M,2) vectors grouped by idx (M,) into (n,2) (bincount: no Python loop over pairs)."""
    return np.column_stack([np.bincount(idx, vecs[:, 0], n), np.bincount(idx, vecs[:, 1], n)])


def neighbour_pairs(pos_i, pos_j, r_c, same=True, use_tree=False):
    """Ordered pairs (i, j, r_ij) with r_ij = |pos_i[i] - pos_j[j]| <= r_c (and i != j if ``same``)."""
    if use_tree:
        m = cKDTree(pos_i).sparse_distance_matrix(cKDTree(pos_j), r_c, output_type="ndarray")
        i, j, r = m["i"].astype(np.int64), m["j"].astype(np.int64), m["v"]
        if same:  # (sparse_distance_matrix leaves out exactly coincident pairs, r = 0: no direction anyway)
            keep = i != j
            i, j, r = i[keep], j[keep], r[keep]
        return i, j, r
    d = np.hypot(pos_i[:, None, 0] - pos_j[None, :, 0], pos_i[:, None, 1] - pos_j[None, :, 1])
    mask = d <= r_c
    if same:
        np.fill_diagonal(mask, False)
    i, j = np.nonzero(mask)
    return i, j, d[i, j]


# ------------------------------------------------------------------------------ the terms
def repulsion(pos_i, pos_j, i, j, r, p: FlockingParams, n):
    """Σ_j v_ij_rep (eq. 1-2): p_rep (r0_rep - r_ij) (r_i - r_j)/r_ij for r_ij < r0_rep. (n,2) m/s."""
    k = r < p.r0_rep_m
    i, j, r = i[k], j[k], r[k]
    u, _ = _unit(pos_i[i] - pos_j[j])
    return _sum_by(i, (p.p_rep_ps * (p.r0_rep_m - r))[:, None] * u, n)


def friction(vel_i, vel_j, i, j, r, p: FlockingParams, n):
    """Σ_j v_ij_frict (eq. 4-6, SPEC sign): -C (v_ij - v_max_ij) (v_i - v_j)/v_ij if v_ij > v_max_ij."""
    dv = vel_i[i] - vel_j[j]
    u, vij = _unit(dv)
    vmax = np.maximum(p.v_frict_mps, D(r - p.r0_frict_m, p.a_frict_mps2, p.p_frict_ps))
    mag = np.where(vij > vmax, -p.c_frict * (vij - vmax), 0.0)
    return _sum_by(i, mag[:, None] * u, n)


def shill(vel, dist, normal, p: FlockingParams, v_obj=None):
    """Shill term (eq. 7-8) for (E, S) ego-shill pairs; returns the (E, 2) sum over S.

    dist (E,S) m: distance to the shill's point (0 when on the wrong side / inside);
    normal (E,S,2): unit direction of the shill velocity; v_obj (E,S,2) or None: velocity of the
    object carrying the shill (moving obstacles), added to v_shill·normal.
    """
    v_s = p.v_shill_mps * normal
    if v_obj is not None:
        v_s = v_s + v_obj
    dv = v_s - vel[:, None, :]
    if p.shill_normal_only:  # road adaptation: only the velocity across the wall/obstacle face counts
        dv = (dv * normal).sum(-1)[..., None] * normal
    u, v_is = _unit(dv)
    vmax = D(dist - p.r0_shill_m, p.a_shill_mps2, p.p_shill_ps)
    mag = np.where(v_is > vmax, v_is - vmax, 0.0)
    return (mag[..., None] * u).sum(axis=1)


def segment_shills(pos, seg_a, seg_b, inward, outside):
    """Nearest points of wall segments: distances (E,S) and shill directions (E,S,2).

    seg_a, seg_b (S,2) segment ends; inward (S,2) unit normals into the allowed area; outside (E,)
    bool: the ego is outside the allowed area. A segment whose inner side the ego is not on while
    the ego is outside gets distance 0 (SPEC §1: full correction back into the area).
    """
    d = seg_b - seg_a
    l2 = np.maximum((d * d).sum(1), 1e-12)
    rel = pos[:, None, :] - seg_a[None]
    t = np.clip((rel * d[None]).sum(-1) / l2, 0.0, 1.0)
    near = seg_a[None] + t[..., None] * d[None]
    dist = _norm(pos[:, None, :] - near)
    wrong = ((pos[:, None, :] - near) * inward[None]).sum(-1) < 0
    dist = np.where(wrong & outside[:, None], 0.0, dist)
    return dist, np.broadcast_to(inward[None], dist.shape + (2,))


def polygon_shills(pos, polys):
    """One shill per convex polygon obstacle. polys (O,K,2) CCW vertices (pad by repeating the last).

    Returns dist (E,O) (0 inside) and direction (E,O,2) away from the obstacle: from its nearest
    boundary point to the ego outside, the outward normal of the nearest edge inside.
    """
    a = polys
    b = np.roll(polys, -1, axis=1)
    d = b - a  # (O,K,2)
    ln = _norm(d)
    valid = ln > 1e-9
    out_n = np.where(valid[..., None], np.stack([d[..., 1], -d[..., 0]], -1) / np.maximum(ln, 1e-9)[..., None], 0.0)
    rel = pos[:, None, None, :] - a[None]  # (E,O,K,2)
    t = np.clip((rel * d[None]).sum(-1) / np.maximum(ln ** 2, 1e-12)[None], 0.0, 1.0)
    near = a[None] + t[..., None] * d[None]
    dk = _norm(pos[:, None, None, :] - near)  # (E,O,K)
    k = np.argmin(dk, axis=2)
    take = lambda arr: np.take_along_axis(arr, k[..., None, None], axis=2)[:, :, 0]  # noqa: E731
    nearest = take(near)
    dist = np.take_along_axis(dk, k[..., None], axis=2)[..., 0]
    signed = np.where(valid[None], (rel * out_n[None]).sum(-1), -np.inf)  # >0 outside that edge
    inside = (signed <= 0).all(axis=2)
    away, _ = _unit(pos[:, None, :] - nearest)
    inner_n = np.take_along_axis(out_n[None].repeat(len(pos), 0), np.argmax(signed, axis=2)[..., None, None],
                                 axis=2)[:, :, 0]
    direction = np.where(inside[..., None] | (dist[..., None] < 1e-9), inner_n, away)
    return np.where(inside, 0.0, dist), direction


def combine(v_tilde, p: FlockingParams):
    """Eq. 10 (cutoff) or the reference simulator's rescale to v_flock."""
    u, n = _unit(v_tilde)
    speed = np.minimum(n, p.v_max_mps) if p.speed_rule == "cutoff" else np.full_like(n, p.v_flock_mps)
    return u * speed[:, None]


# ------------------------------------------------------------------------------ controller
class FlockingController:
    """Vásárhelyi flocking (SPEC §1): repulsion, alignment, walls and obstacles as shill agents."""

    needs = Needs(goals=False, v2v=True)  # a flock has no goal; members' states come over V2V
    metrics = ("flocking",)  # order parameters and fitness (sumo_avoid.metrics.flocking)

    def __init__(self, params: FlockingParams, ctx=None):
        self.p = params
        self.tasks: set[str] = set()
        self._area = None
        self._walls = (np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)))
        if ctx is not None and ctx.walls is not None:
            self.set_walls(ctx.walls)
        elif ctx is not None and ctx.road is not None:
            self._set_area(ctx.road.area)
        self._last_update = -np.inf
        self._cache: dict[str, np.ndarray] = {}
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
        self.tasks.add(task.vid)

    def remove_ego(self, vid: str) -> None:
        self.tasks.discard(vid)
        self._cache.pop(vid, None)

    def stats(self) -> dict:
        return {"flocking_updates": self.updates}

    def tables(self) -> dict:
        return {}

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
        i, j, r = neighbour_pairs(own_pos, nb_pos, p.r_c_m, same=True, use_tree=e >= p.kdtree_min_agents)
        u, spd = _unit(own_vel)
        hd = np.column_stack([np.cos(heading), np.sin(heading)])
        u = np.where((spd > 1e-6)[:, None], u, hd)
        v = p.v_flock_mps * u
        v = v + repulsion(own_pos, nb_pos, i, j, r, p, e) + friction(own_vel, nb_vel, i, j, r, p, e)
        a, b, inward = self._walls
        if len(a):
            dist, nrm = segment_shills(own_pos, a, b, inward, self.outside(own_pos))
            v = v + shill(own_vel, dist, nrm, p)
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
        if not due and all(v in self._cache for v in obs.ego_ids):
            return np.array([self._cache[v] for v in obs.ego_ids]).reshape(-1, 2)
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
        out = self.desired(own_pos, own_vel, snap.heading[rows], nb_pos, nb_vel, obs.obstacles, others)
        self._cache = {v: out[k] for k, v in enumerate(obs.ego_ids)}
        self._last_update = snap.time_s
        self.updates += 1
        return out
