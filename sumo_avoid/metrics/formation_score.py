"""Seed 003's scene-adaptation evaluator S_ef = I_t + I_e + I_d (SPEC §3) of a formation run,
the modes' time shares and obstacle contacts. Smaller S_ef is better; each term is dimensionless:

* ``i_t`` convergence-time ratio: T / T_ref, T = time until every member's centre came within
  ``ego.goal_tolerance_m`` of its goal (the run's simulated time if one never did), T_ref = the
  straight-line distance from the leader's first recorded position to its goal over
  ``leader_speed_mps``. 1 = a straight run at the leader's speed.
* ``i_e`` energy-consumption rate: sum over members of the integral of |a| |v| dt, over the sum of
  the members' path lengths (the integral of |v| dt), divided by the actuator's
  ``max_accel_mps2``: the path-weighted mean 2-D acceleration (longitudinal and lateral) as a
  fraction of the car's largest acceleration. Velocities are the recorded (vx, vy); a = their
  finite difference per recorded step.
* ``i_d`` formation distortion: the time mean, over recorded steps with the leader and at least one
  follower present, of the RMS over followers of |x_i - slot_i|, over the formation's size D.
  slot_i = the leader's recorded position + the nominal (kappa = 1, unscaled) slot turned by the
  leader's recorded heading, so narrowing (kappa 2) and breaking up (kappa 3) count as distortion;
  D = RMS distance of the nominal slots from the leader (17.5 m for the triangle of 6 at 8 m).

Also: ``obstacle_hits`` (contact episodes of a member's footprint with a static obstacle
polygon), ``obstacle_min_gap_m`` (the smallest footprint-to-obstacle distance of any member, m,
among obstacles within ``NEAR_M`` of its circumcircle; None if none came that near), ``kappa1_share`` .. ``kappa3_share`` (fraction of the controller's steps in each mode,
``formation_kappa_steps``), ``formation_time_s`` (T, None if a member never arrived).
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.geometry import (
    convex_distance,
    convex_overlap,
    footprint_corners,
    pad_polygons,
)
from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.planning import formation_shape as ff
from sumo_avoid.planning.formation_shape import member_order
from sumo_avoid.rollout.result import RunResult

NEAR_M = 5.0  # obstacle_min_gap_m looks at obstacles within this of a footprint's circumcircle, m


def _tracks(run: RunResult, order):
    """(T,) times and (M, T, k) arrays of x, y, vx, vy, heading, length, width (NaN where absent)."""
    ego = run.traj[run.traj["is_ego"]]
    times = np.unique(ego["time_s"].to_numpy())
    col = {v: k for k, v in enumerate(order)}
    m = ego["id"].map(col).to_numpy()
    keep = ~np.isnan(m.astype(float))
    t = np.searchsorted(times, ego["time_s"].to_numpy()[keep])
    out = np.full((len(order), len(times), 7), np.nan)
    out[m[keep].astype(int), t] = ego[["x", "y", "vx", "vy", "heading", "length", "width"]].to_numpy()[keep]
    return times, out


def energy_rate(times, tr, a_ref: float) -> float:
    """I_e: sum of integral |a||v| dt over sum of integral |v| dt, over a_ref (see the module doc)."""
    num = den = 0.0
    for x in tr:  # per member (a handful)
        ok = ~np.isnan(x[:, 0])
        t, v = times[ok], x[ok][:, 2:4]
        if len(t) < 2:
            continue
        dt = np.diff(t)
        a = np.diff(v, axis=0) / dt[:, None]
        vm = np.hypot(*(0.5 * (v[1:] + v[:-1])).T)
        num += float((np.hypot(*a.T) * vm * dt).sum())
        den += float((vm * dt).sum())
    return num / den / a_ref if den > 0 else 0.0


def distortion(tr, offsets) -> float:
    """I_d: time-mean RMS slot error of the followers over the shape's RMS slot distance."""
    lead = tr[0]
    D = float(np.sqrt((offsets[1:] ** 2).sum(axis=1).mean())) if len(offsets) > 1 else 1.0
    c, s = np.cos(lead[:, 4]), np.sin(lead[:, 4])
    sx = lead[None, :, 0] + c[None] * offsets[1:, 0, None] - s[None] * offsets[1:, 1, None]
    sy = lead[None, :, 1] + s[None] * offsets[1:, 0, None] + c[None] * offsets[1:, 1, None]
    e2 = (tr[1:, :, 0] - sx) ** 2 + (tr[1:, :, 1] - sy) ** 2  # (F, T), NaN where absent
    have = ~np.isnan(e2)
    use = have.any(axis=0) & ~np.isnan(lead[:, 0])
    if not use.any():
        return 0.0
    rms = np.sqrt(np.nansum(np.where(have, e2, 0.0), axis=0)[use] / have.sum(axis=0)[use])
    return float(rms.mean() / D)


def arrival_time(times, tr, goals, tol: float) -> float | None:
    """First time every member had come within ``tol`` of its goal (None if one never did)."""
    worst = 0.0
    for x, g in zip(tr, goals):
        d = np.hypot(x[:, 0] - g[0], x[:, 1] - g[1])
        hit = np.flatnonzero(d <= tol)
        if not len(hit):
            return None
        worst = max(worst, float(times[hit[0]]))
    return worst


def obstacle_contacts(times, tr, polys) -> tuple[int, float | None]:
    """(contact episodes (consecutive recorded steps) of member footprints with obstacle polygons,
    the smallest footprint-to-obstacle distance over the run, m; None without obstacles nearby)."""
    if not len(polys):
        return 0, None
    P = pad_polygons(polys)
    cen = P.mean(axis=1)
    rad = np.hypot(*(P - cen[:, None]).transpose(2, 0, 1)).max(axis=1)
    hits, gap = 0, np.inf
    for x in tr:
        ok = np.flatnonzero(~np.isnan(x[:, 0]))
        pos = x[ok, :2]
        d = np.hypot(pos[:, None, 0] - cen[None, :, 0], pos[:, None, 1] - cen[None, :, 1])
        k, o = np.nonzero(d <= rad[None] + 0.5 * np.hypot(x[ok, 5], x[ok, 6])[:, None] + NEAR_M)
        if not len(k):
            continue
        fp = footprint_corners(pos[k], x[ok[k], 4], x[ok[k], 5], x[ok[k], 6])
        gap = min(gap, float(convex_distance(fp, P[o])[0].min()))
        touch = convex_overlap(fp, P[o])
        contact = np.zeros((len(ok), len(P)), bool)
        contact[k[touch], o[touch]] = True
        starts = contact & ~np.vstack([np.zeros((1, len(P)), bool), contact[:-1]])
        hits += int(starts.sum())
    return hits, (gap if np.isfinite(gap) else None)


class FormationScore(Metric):
    """S_ef = I_t + I_e + I_d (SPEC §3), kappa time shares, obstacle contacts (none of them when no
    member has a goal)."""

    keys = Keys(("s_ef", "i_t", "i_e", "i_d", "formation_time_s", "t_ref_s", "obstacle_hits", "obstacle_min_gap_m",
                 "kappa1_share", "kappa2_share", "kappa3_share"))

    def compute(self, run: RunResult) -> dict:
        spec = run.scenario.spec
        p = run.scenario.controller_params["formation"]
        order = [v for v in member_order(p, run.goals) if v in run.goals]
        if not order:
            return {}
        times, tr = _tracks(run, order)
        offsets = ff.slots(p.shape, len(order), p.spacing_m, p.apex_deg)
        goals = [run.goals[v] for v in order]
        first = tr[0][np.flatnonzero(~np.isnan(tr[0][:, 0]))[0], :2]
        t_ref = float(np.hypot(*(np.asarray(goals[0]) - first))) / p.leader_speed_mps
        T = arrival_time(times, tr, goals, spec.ego.goal_tolerance_m)
        i_t = (T if T is not None else run.sim_time_s) / t_ref if t_ref > 0 else 0.0
        i_e = energy_rate(times, tr, run.scenario.table("actuators.kinematic").max_accel_mps2)
        i_d = distortion(tr, offsets)
        steps = np.asarray(run.stats.get("formation_kappa_steps", [0, 0, 0]), float)
        share = steps / steps.sum() if steps.sum() > 0 else np.zeros(3)
        hits, gap = obstacle_contacts(times, tr, run.scene.obstacles)
        return {"s_ef": i_t + i_e + i_d, "i_t": i_t, "i_e": i_e, "i_d": i_d, "formation_time_s": T,
                "t_ref_s": t_ref, "obstacle_hits": hits, "obstacle_min_gap_m": gap,
                "kappa1_share": share[0], "kappa2_share": share[1], "kappa3_share": share[2]}
