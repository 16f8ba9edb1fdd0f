"""Metrics of a finished run, computed from its recorded table, and the run's output files.

``metrics.json`` holds only simulation results (no wall-clock fields), written with sorted keys,
so the same scenario and seed give a byte-identical file. Timings go to ``timings.json``.
"""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import pandas as pd

from sumo_avoid import __version__
from sumo_avoid.metrics import basic as metrics
from sumo_avoid.core.geometry import footprint_corners, pairwise_footprint_distance
from sumo_avoid.rollout.runner import RunResult


def _clean(x):
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def ego_outside_distance(res: RunResult) -> np.ndarray:
    ego = res.traj[res.traj["is_ego"]]
    if ego.empty:
        return np.zeros(0)
    corners = footprint_corners(ego[["x", "y"]].to_numpy(), ego["heading"].to_numpy(),
                                ego["length"].to_numpy(), ego["width"].to_numpy())
    return res.road.footprint_outside_distance(corners)


def compute(res: RunResult) -> dict:
    spec = res.scenario.spec
    traj = res.traj
    events = metrics.collision_events(traj)
    sumo = res.sumo_events
    ours = {tuple(sorted(p)) for p in zip(events["a"], events["b"])}
    theirs = {tuple(sorted(p)) for p in zip(sumo["a"], sumo["b"])}
    motion = metrics.motion_summary(traj, res.goals, spec.ego.goal_tolerance_m)
    out = {
        "scenario": spec.name,
        "controller": spec.ego.controller,
        "sensor": spec.ego.sensor,
        "safety": spec.ego.safety,
        "seed": spec.sim.seed,
        "step_s": spec.sim.step_s,
        "sim_time_s": res.sim_time_s,
        "steps": res.steps,
        "collisions": int(len(events)),
        "collision_events": events.to_dict(orient="records"),
        "sumo_collisions": int(len(sumo)),
        "sumo_collision_events": sumo.to_dict(orient="records"),
        "collision_pairs_only_ours": sorted(map(list, ours - theirs)),
        "collision_pairs_only_sumo": sorted(map(list, theirs - ours)),
        "min_gap_m": metrics.min_gap_m(traj),
        "phi_coll": metrics.phi_coll(traj, spec.sim.step_s),
        "phi_wall": metrics.phi_wall(ego_outside_distance(res)),
        "sumo_avoid_version": __version__,
        **res.controller_stats,
        **motion,
    }
    if spec.ego.controller == "flocking":
        out.update(flocking_compute(res, out["phi_coll"], out["phi_wall"]))
    return _clean(out)


def flocking_compute(res: RunResult, phi_coll: float, road_phi_wall: float) -> dict:
    """SPEC §1.1-1.2 order parameters, partial fitnesses and μ. In an arena φ_wall uses the vehicle
    centres against the square and the obstacles; on a road it is the road footprint value."""
    from sumo_avoid.rollout.arena import outside_distance
    from sumo_avoid.order import flocking_metrics

    p = res.scenario.params
    phi_wall = road_phi_wall
    if res.walls is not None:
        ego = res.traj[res.traj["is_ego"]]
        phi_wall = metrics.phi_wall(outside_distance(ego[["x", "y"]].to_numpy(), res.walls, res.obstacles))
    return flocking_metrics(res.traj, v_flock=p.v_flock_mps, r_c_m=p.r_c_m, phi_coll=phi_coll, phi_wall=phi_wall)


def series(res: RunResult) -> pd.DataFrame:
    """Per step: smallest ego-to-other footprint gap and the mean ego speed (for plots)."""
    rows = []
    for step, g in res.traj.groupby("step", sort=True):
        ego = g["is_ego"].to_numpy()
        if not ego.any():
            continue
        c = footprint_corners(g[["x", "y"]].to_numpy(), g["heading"].to_numpy(), g["length"].to_numpy(),
                              g["width"].to_numpy())
        gap = np.nan
        if len(g) > 1:
            d = pairwise_footprint_distance(c[ego], c)
            d[np.arange(ego.sum()), np.flatnonzero(ego)] = np.inf
            gap = float(d.min())
        rows.append((float(g["time_s"].iloc[0]), gap, float(g.loc[ego, "speed"].mean())))
    return pd.DataFrame(rows, columns=["time_s", "min_gap_m", "ego_speed_mps"])


def write_outputs(res: RunResult, out_dir: pathlib.Path, plots: bool = True) -> dict:
    out_dir.mkdir(parents=True, exist_ok=True)
    m = compute(res)
    (out_dir / "metrics.json").write_text(json.dumps(m, indent=2, sort_keys=True) + "\n")
    (out_dir / "timings.json").write_text(json.dumps(_clean(res.timings), indent=2, sort_keys=True) + "\n")
    res.traj.to_csv(out_dir / "trajectories.csv", index=False)
    if getattr(res, "radar_log", None):  # radar.log_detections = true
        from sumo_avoid.sensing.log import detections_table

        detections_table(res.radar_log).to_csv(out_dir / "detections.csv", index=False)
    if plots:
        from sumo_avoid.plots.trajectories import plot_timeseries, plot_trajectories

        events = pd.DataFrame(m["collision_events"], columns=["step", "time_s", "a", "b", "x", "y"])
        title = (f"{m['scenario']} · {m['controller']} · seed {m['seed']} · collisions {m['collisions']}"
                 f" · goal {'reached' if m['goal_reached'] else 'NOT reached'}")
        plot_trajectories(res.road, res.traj, out_dir / "trajectory.png", collisions=events, goals=res.goals,
                          title=title)
        plot_timeseries(series(res), out_dir / "timeseries.png", title=title)
        if res.walls is not None or res.obstacles:  # flock in an arena / obstacles: walls and polygons drawn
            from sumo_avoid.studies.reproduce import plot_arena

            plot_arena(res, out_dir / "arena.png", f"{m['scenario']} · seed {m['seed']} · mu {m.get('mu', 0):.3f}")
    return m
