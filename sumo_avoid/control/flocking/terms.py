"""The terms of the flocking model (SPEC §1, seed 000 eq. 1-10) and its parameters, pure numpy.

Shared by the controller in the plane (:mod:`sumo_avoid.control.flocking.flocking`: the arena, and no road
given) and on roads in each ego's route frame (:mod:`sumo_avoid.control.flocking.road_flock`).
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from scipy.spatial import cKDTree

from sumo_avoid.control.flocking.pair_terms import pair_sums, tree_pair_sums, wall_shill_sums
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.curves import braking_curve_D as D
from sumo_avoid.core.geometry import unit_norm

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
                                                "0 = off; sumo_avoid/core/noise.py)")
    gps_lambda_ps: float = field_doc(0.1, doc="GPS error damping lambda, 1/s")
    shill_normal_only: bool = field_doc(False, doc="road adaptation (not SPEC): the shill term sees only the velocity "
                                                   "difference along the wall/obstacle normal (default off = eq. 8)")
    vehicles_as_obstacles: bool = field_doc(True, doc="non-ego vehicles are moving obstacles (shill term)")
    v2v_gate_m: float = field_doc(4.0, doc="sensor = 'radar': a return whose box centre lies this close to a flock "
                                           "member's V2V position (extrapolated by delay_s) is that member "
                                           "and is dropped (its V2V state is used), m")
    kdtree_min_agents: int = field_doc(100, doc="use scipy cKDTree for neighbour pairs from this many egos on")
    curve_lat_accel_mps2: float = field_doc(2.5, doc="on roads: speed for the road ahead, lateral acceleration in "
                                                     "bends (SPEC §5), m/s^2")
    curve_decel_mps2: float = field_doc(3.0, doc="on roads: speed for the road ahead, braking before a bend, m/s^2")
    wall_margin_m: float = field_doc(0.3, doc="on roads: the braking-curve bound on the speed towards a road edge stops "
                                              "the footprint this far inside it (the car's heading lags its command), m")
    max_course_deg: float = field_doc(35.0, doc="on roads, moving forward: the desired direction stays within this angle "
                                                "of the road's (a car cannot move sideways), deg")
    max_lat_speed_mps: float = field_doc(1.5, doc="on roads: the desired speed across the road stays below this, m/s")
    side_gap_m: float = field_doc(0.5, doc="on roads: clearance the braking-curve bound keeps to a vehicle beside the "
                                           "ego, and the margin within which one ahead counts as in its strip, m")
    road_gap_m: float = field_doc(2.0, doc="on roads: gap to a vehicle ahead in the ego's strip at which the braking "
                                           "curve (a_shill, p_shill) asks the ego to match its speed, m")

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
        for k in ("a_frict_mps2", "p_frict_ps", "a_shill_mps2", "p_shill_ps", "r_c_m", "curve_lat_accel_mps2",
                  "curve_decel_mps2"):
            if getattr(self, k) <= 0:
                raise ValueError(f"{k} must be > 0")


def preset(name: str, **overrides) -> FlockingParams:
    """``FlockingParams`` with seed Table 3's values for ``paper_v4`` / ``paper_v6`` / ``paper_v8``."""
    return FlockingParams(**{**PRESETS[name], **overrides})


# ------------------------------------------------------------------------------ vector helpers
def _norm(v):
    return np.hypot(v[..., 0], v[..., 1])


def _sum_by(idx, vecs, n):
    """Σ of (M,2) vectors grouped by idx (M,) into (n,2) (bincount: no Python loop over pairs)."""
    return np.column_stack([np.bincount(idx, vecs[:, 0], n), np.bincount(idx, vecs[:, 1], n)])


def neighbour_pairs(pos_i, pos_j, r_c, same=True, use_tree=False):
    """Ordered pairs (i, j, r_ij) with r_ij = |pos_i[i] - pos_j[j]| <= r_c (and i != j if ``same``)."""
    if use_tree:
        tree = cKDTree(pos_i)  # one tree when both sets are the same points (the same tree as two identical ones)
        other = tree if pos_j is pos_i or np.array_equal(pos_i, pos_j) else cKDTree(pos_j)
        m = tree.sparse_distance_matrix(other, r_c, output_type="ndarray")
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
def pair_terms(pos_i, pos_j, vel_i, vel_j, i, j, r, p: FlockingParams, n):
    """(repulsion (n,2), friction (n,2)): :func:`repulsion` and :func:`friction` in one compiled loop
    (:func:`sumo_avoid.control.flocking.pair_terms.pair_sums`, the same values)."""
    return pair_sums(np.ascontiguousarray(pos_i, float), np.ascontiguousarray(pos_j, float),
                     np.ascontiguousarray(vel_i, float), np.ascontiguousarray(vel_j, float),
                     np.asarray(i, np.int64), np.asarray(j, np.int64), np.asarray(r, float), n,
                     p.r0_rep_m, p.p_rep_ps, p.r0_frict_m, p.c_frict, p.v_frict_mps, p.a_frict_mps2, p.p_frict_ps)


def neighbour_terms(pos_i, pos_j, vel_i, vel_j, p: FlockingParams, use_tree=False):
    """(repulsion (n,2), friction (n,2)) over the neighbours within ``p.r_c_m`` (i != j): :func:`neighbour_pairs`
    then :func:`pair_terms`; with ``use_tree`` the search and the sums are one compiled pass
    (:func:`~sumo_avoid.control.flocking.pair_terms.tree_pair_sums`) that adds each ego's terms in the order
    the cKDTree search yields them, so the sums are the same bits without the pair arrays."""
    if not use_tree:
        i, j, r = neighbour_pairs(pos_i, pos_j, p.r_c_m, same=True)
        return pair_terms(pos_i, pos_j, vel_i, vel_j, i, j, r, p, len(pos_i))
    pos_j = np.ascontiguousarray(pos_j, float)
    return tree_pair_sums(np.ascontiguousarray(pos_i, float), pos_j, np.ascontiguousarray(vel_i, float),
                          np.ascontiguousarray(vel_j, float), cKDTree(pos_j).indices.astype(np.int64, copy=False),
                          float(p.r_c_m), True, p.r0_rep_m, p.p_rep_ps, p.r0_frict_m, p.c_frict, p.v_frict_mps,
                          p.a_frict_mps2, p.p_frict_ps)


def repulsion(pos_i, pos_j, i, j, r, p: FlockingParams, n):
    """Σ_j v_ij_rep (eq. 1-2): p_rep (r0_rep - r_ij) (r_i - r_j)/r_ij for r_ij < r0_rep. (n,2) m/s."""
    k = r < p.r0_rep_m
    i, j, r = i[k], j[k], r[k]
    u, _ = unit_norm(pos_i[i] - pos_j[j])
    return _sum_by(i, (p.p_rep_ps * (p.r0_rep_m - r))[:, None] * u, n)


def friction(vel_i, vel_j, i, j, r, p: FlockingParams, n):
    """Σ_j v_ij_frict (eq. 4-6, SPEC sign): -C (v_ij - v_max_ij) (v_i - v_j)/v_ij if v_ij > v_max_ij."""
    dv = vel_i[i] - vel_j[j]
    u, vij = unit_norm(dv)
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
    u, v_is = unit_norm(dv)
    vmax = D(dist - p.r0_shill_m, p.a_shill_mps2, p.p_shill_ps)
    mag = np.where(v_is > vmax, v_is - vmax, 0.0)
    return (mag[..., None] * u).sum(axis=1)


def wall_shills(pos, vel, seg_a, seg_b, inward, outside, p: FlockingParams):
    """``shill(vel, *segment_shills(pos, seg_a, seg_b, inward, outside), p)`` in one compiled loop
    (:func:`~sumo_avoid.control.flocking.pair_terms.wall_shill_sums`, the same values). (E, 2) m/s."""
    return wall_shill_sums(np.ascontiguousarray(pos, float), np.ascontiguousarray(vel, float),
                           np.ascontiguousarray(seg_a, float), np.ascontiguousarray(seg_b, float),
                           np.ascontiguousarray(inward, float), np.ascontiguousarray(outside, bool),
                           p.v_shill_mps, p.r0_shill_m, p.a_shill_mps2, p.p_shill_ps, bool(p.shill_normal_only))


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
    take = lambda arr: np.take_along_axis(arr, k[..., None, None], axis=2)[:, :, 0]
    nearest = take(near)
    dist = np.take_along_axis(dk, k[..., None], axis=2)[..., 0]
    signed = np.where(valid[None], (rel * out_n[None]).sum(-1), -np.inf)  # >0 outside that edge
    inside = (signed <= 0).all(axis=2)
    away, _ = unit_norm(pos[:, None, :] - nearest)
    inner_n = np.take_along_axis(out_n[None].repeat(len(pos), 0), np.argmax(signed, axis=2)[..., None, None],
                                 axis=2)[:, :, 0]
    direction = np.where(inside[..., None] | (dist[..., None] < 1e-9), inner_n, away)
    return np.where(inside, 0.0, dist), direction


def combine(v_tilde, p: FlockingParams):
    """Eq. 10 (cutoff) or the reference simulator's rescale to v_flock."""
    u, n = unit_norm(v_tilde)
    speed = np.minimum(n, p.v_max_mps) if p.speed_rule == "cutoff" else np.full_like(n, p.v_flock_mps)
    return u * speed[:, None]
