"""The formation controller's safety shield: a velocity barrier no choice of gains can override.

The potential field (:mod:`.field`) only *prefers* distance from an obstacle: how much
depends on eta_re / eta_at, and a tuner that is scored on speed learns to weaken the repulsion. The
shield is applied to
every member's velocity command after the field, and keeps for each hazard the discrete-time
barrier condition (a control-barrier-function constraint on a single integrator)

    (v - v_hazard) . n  >=  -k h            h = free distance beyond a margin, m; k (1/s)

with n the unit vector from the hazard's nearest point towards the vehicle: the approach speed
is at most k times the free distance, so h decays at most like exp(-k t) and never reaches 0 while
the actuator follows the command (the first-order velocity lag tau of the relaxation actuator adds
the factor exp(k tau) = 1.28 at k = 0.5 1/s, tau = 0.5 s; the margin covers the step). The
command is changed only where a constraint is violated, by the smallest change along n.

Two hazard models (see :func:`disc_hazards`, :func:`footprint_hazards`):

* **static obstacles**: the vehicle as the disc of its half diagonal about its centre, so no
  heading can put a corner into the obstacle (with the relaxation actuator the heading follows the
  velocity and can swing round at low speed);
* **vehicles** (non-members): footprint to footprint, relative to the other's velocity;
* **other members**, relative to the other's current (V2V) velocity, each member taking half of
  the allowed approach (both run the same shield), so while the velocities follow the commands the
  pair keeps ``-k h`` together: as discs of their half diagonals (``member_disc``; safe at any
  headings: with the relaxation actuator two slow members' headings can swing round within one
  step, corners into each other, while their centres stay metres apart) or footprint to footprint (a
  car's yaw rate is bounded; lane-wide slots
  on a road need the footprints: 3.5 m between centres is less than two half diagonals).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from sumo_avoid.core.geometry import convex_distance, footprint_corners, unit_norm

#: heading_cap never slows a car below this, m/s.
CREEP_MPS = 0.5


class Members(NamedTuple):
    """The members' own poses (E, 2) / (E,) and the others' V2V positions and velocities (E, 2)."""
    pos: np.ndarray
    heading: np.ndarray
    length: np.ndarray
    width: np.ndarray
    nb_pos: np.ndarray
    nb_vel: np.ndarray



def disc_hazards(pos, radius, polys, centroid):
    """Static obstacles against each ego's disc: pos (E, 2) centres, radius (E,) m, polys (O, K, 2),
    centroid (O, 2). Returns (n (E, O, 2) unit vectors from the obstacle towards the ego, gap (E, O)
    m = centre-to-polygon distance - radius, negative when the disc overlaps)."""
    E, O = len(pos), len(polys)
    pts = np.repeat(np.asarray(pos, float), O, axis=0)[:, None, :]
    d, _, on_obs = convex_distance(pts, np.tile(polys, (E, 1, 1)))
    n, _ = unit_norm(pts[:, 0] - on_obs)
    inside = d <= 1e-9  # centre inside the polygon: away from its centroid
    n = np.where(inside[:, None], unit_norm(pts[:, 0] - np.tile(centroid, (E, 1)))[0], n)
    return n.reshape(E, O, 2), d.reshape(E, O) - np.repeat(radius, O).reshape(E, O)


def member_disc_hazards(pos, radius, nb_pos):
    """Members against each other as discs: centres pos (E, 2) (own, now), radius (E,) m, nb_pos (E, 2)
    (the others' V2V positions). Returns (n (E, E, 2) unit vectors from member j's centre towards
    member i's (0 where they coincide), gap (E, E) m = centre distance - r_i - r_j)."""
    n, cc = unit_norm(np.asarray(pos, float)[:, None, :] - np.asarray(nb_pos, float)[None, :, :])
    return n, cc - radius[:, None] - radius[None, :]


def footprint_hazards(own, others, own_pos, other_pos):
    """Footprints against footprints: own (E, 4, 2), others (O, 4, 2), centres own_pos (E, 2),
    other_pos (O, 2). Returns (n (E, O, 2) from the other's nearest point towards the ego (centre to
    centre when in contact), gap (E, O) m, 0 in contact)."""
    E, O = len(own), len(others)
    d, on_a, on_b = convex_distance(np.repeat(own, O, axis=0), np.tile(others, (E, 1, 1)))
    n, ln = unit_norm(on_a - on_b)
    c, _ = unit_norm(np.repeat(own_pos, O, axis=0) - np.tile(other_pos, (E, 1)))
    n = np.where((ln > 1e-6)[:, None], n, c)
    return n.reshape(E, O, 2), d.reshape(E, O)


def barrier(v, n, bound, passes: int = 20, slide: float = 0.0) -> np.ndarray:
    """Velocity commands v (E, 2) changed as little as needed so that v . n[e, c] >= bound[e, c]
    for every constraint c (n (E, C, 2) unit vectors, bound (E, C) m/s; -inf = inactive).

    Each pass moves every ego's command onto its most violated constraint's line (Motzkin's
    relaxation method: converges to a point of the intersection of the half-planes when it is not
    empty; in 2-D a few passes suffice); ``passes`` bounds the work. ``slide``: the command found is
    then also moved ``slide`` times the correction's size along the first violated constraint's n
    turned 90 deg to the left (the hazard's tangent; no change to that constraint), so a command
    straight into a hazard slides round it instead of stopping dead (a follower whose slot lies
    behind an obstacle), but only where that keeps every constraint (between two hazards sliding
    along one drives into the other). Returns (E, 2)."""
    v = np.array(v, float).reshape(-1, 2)
    if n.shape[1] == 0:
        return v
    rows = np.arange(len(v))
    first = None
    out = v.copy()
    for _ in range(passes):
        viol = bound - np.einsum("ecj,ej->ec", n, out)  # > 0: violated by that much
        c = viol.argmax(axis=1)
        worst = viol[rows, c]
        if not (worst > 1e-9).any():
            break
        first = c if first is None else first
        out += np.where(worst > 1e-9, worst, 0.0)[:, None] * n[rows, c]
    if slide == 0.0 or first is None:
        return out
    nc = n[rows, first]
    slid = out + slide * np.hypot(*(out - v).T)[:, None] * np.column_stack([-nc[:, 1], nc[:, 0]])
    ok = (np.einsum("ecj,ej->ec", n, slid) >= bound - 1e-9).all(axis=1)
    return np.where(ok[:, None], slid, out)


def approach_bounds(n, gap, margin_m: float, k_ps: float, hazard_vel=None, share: float = 1.0):
    """Barrier bounds for :func:`barrier`: v . n >= hazard_vel . n - share k (gap - margin).
    hazard_vel (O, 2) or None (static); share 0.5 when the other side runs the same shield."""
    b = -share * k_ps * (np.asarray(gap, float) - margin_m)
    if hazard_vel is not None:
        b = b + np.einsum("eoj,oj->eo", n, np.asarray(hazard_vel, float).reshape(-1, 2))
    return b


def heading_cap(v, heading, n, bound, creep_mps: float = CREEP_MPS) -> np.ndarray:
    """A car moves along its heading (the kinematic actuator drives the desired velocity's component
    along it, v . h, while it turns): the commands v (E, 2) scaled down so that this component keeps
    every constraint, sigma (h . n_c) >= bound_c, i.e. sigma <= bound_c / (h . n_c) where the heading
    points at the hazard (h . n_c < 0); not below ``creep_mps`` (a car turns only while it moves: at
    0 one facing a hazard could never turn away) unless a hazard it faces (h . n < -0.5) is within
    the margin already (bound >= 0): then 0, and the car backs off (the actuator reverses towards a command
    behind it) or waits."""
    h = np.column_stack([np.cos(heading), np.sin(heading)])
    hn = np.einsum("ecj,ej->ec", n, h)
    towards = (hn < -1e-9) & np.isfinite(bound)
    cap = np.min(np.where(towards, np.maximum(bound, -1e12) / np.where(towards, hn, -1.0), np.inf), axis=1,
                 initial=np.inf)
    room = ~((hn < -0.5) & (bound >= 0.0)).any(axis=1)  # no hazard it faces (within 60 deg) is within the margin
    cap = np.maximum(cap, np.where(room, creep_mps, 0.0))
    sigma = np.einsum("ej,ej->e", v, h)
    f = np.where(sigma > cap, cap / np.maximum(sigma, 1e-12), 1.0)
    return v * f[:, None]


def apply(v, m: Members, polys, mask, static, hazard_vel, margin_m: float, k_ps: float, extra=None,
          slide: float = 0.0, member_disc: bool = True) -> np.ndarray:
    """The shield on the members' commands v (E, 2): static obstacles (``static`` (O,) of polys
    (O, K, 2)) against each member's disc, other vehicles footprint to footprint relative to their
    velocities (``hazard_vel`` (O, 2)), each hazard only for the members that know it (``mask``
    (E, O)), and the other members (discs of their half diagonals if ``member_disc``, else footprint to
    footprint) relative to their V2V velocity, each member taking half of the allowed approach; ``extra``: further (n (E, C, 2), bounds (E, C)), e.g. a
    road's bounds ((n = (0, 1), (0, -1)) in the route frame: the right and the left bound), then
    :func:`heading_cap` on the other constraints (the cap would stop a car that faces the road's edge),
    then the bounds once more, exactly, as limits on d_dot."""
    E = len(v)
    ego = footprint_corners(m.pos, m.heading, m.length, m.width)
    radius = 0.5 * np.hypot(m.length, m.width)
    ns, bs = [np.zeros((E, 0, 2))], [np.zeros((E, 0))]
    if static.any():
        sp = polys[static]
        n, gap = disc_hazards(m.pos, radius, sp, sp.mean(axis=1))
        ns.append(n)
        bs.append(np.where(mask[:, static], approach_bounds(n, gap, margin_m, k_ps), -np.inf))
    if (~static).any():
        veh = polys[~static]
        n, gap = footprint_hazards(ego, veh, m.pos, veh.mean(axis=1))
        ns.append(n)
        bs.append(np.where(mask[:, ~static], approach_bounds(n, gap, margin_m, k_ps, hazard_vel[~static]), -np.inf))
    if E > 1:
        n, gap = member_disc_hazards(m.pos, radius, m.nb_pos) if member_disc else \
            footprint_hazards(ego, footprint_corners(m.nb_pos, m.heading, m.length, m.width), m.pos, m.nb_pos)
        ns.append(n)
        bs.append(np.where(np.eye(E, dtype=bool), -np.inf, approach_bounds(n, gap, margin_m, k_ps, m.nb_vel, 0.5)))
    n, b = np.concatenate(ns, axis=1), np.concatenate(bs, axis=1)
    if extra is None:
        return barrier(v, n, b, slide=slide)
    v = heading_cap(barrier(v, np.concatenate([extra[0], n], axis=1), np.concatenate([extra[1], b], axis=1)),
                    m.heading, n, b)
    # the road wins: a car squeezed between a vehicle and the edge brakes (the cap), it does not leave
    # the road; the bounds' normals are +-d, so their constraints bound d_dot from below and above
    lo, hi = extra[1][:, 0], -extra[1][:, 1]
    v[:, 1] = np.where(lo <= hi, np.clip(v[:, 1], lo, hi), 0.5 * (lo + hi))
    return v
