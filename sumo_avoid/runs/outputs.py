"""The files of one finished run: metrics.json, timings.json, trajectories.csv, the plug-ins'
tables (e.g. detections.csv) and the plots.

``metrics.json`` holds only simulation results (no wall-clock fields), written with sorted keys,
so the same scenario and seed give a byte-identical file. Timings go to ``timings.json``.
"""
from __future__ import annotations

import json
import pathlib

import pandas as pd

from sumo_avoid.metrics import clean, compute
from sumo_avoid.metrics.series import series
from sumo_avoid.plots.arena_plots import plot_arena
from sumo_avoid.plots.formation_plots import plot_formation
from sumo_avoid.plots.planner import plot_convergence, plot_plans
from sumo_avoid.plots.trajectories import plot_timeseries, plot_trajectories
from sumo_avoid.rollout.assemble import metric_names
from sumo_avoid.rollout.result import RunResult


def run_metrics(res: RunResult) -> dict:
    return compute(res, metric_names(res.scenario))


def timings(res: RunResult) -> dict:
    """The run's wall-clock timings, plus a planner's plan times (mean and max over its plans, ms)."""
    out = dict(res.timings)
    plans = res.tables.get("plans")
    if plans is not None and len(plans):
        out.update(plan_ms_mean=float(plans["plan_ms"].mean()), plan_ms_max=float(plans["plan_ms"].max()))
    return out


def write_outputs(res: RunResult, out_dir: pathlib.Path, plots: bool = True) -> dict:
    out_dir.mkdir(parents=True, exist_ok=True)
    m = run_metrics(res)
    (out_dir / "metrics.json").write_text(json.dumps(m, indent=2, sort_keys=True) + "\n")
    (out_dir / "timings.json").write_text(json.dumps(clean(timings(res)), indent=2, sort_keys=True) + "\n")
    res.traj.to_csv(out_dir / "trajectories.csv", index=False)
    for name, table in res.tables.items():
        table.to_csv(out_dir / f"{name}.csv", index=False)
    if plots:
        events = pd.DataFrame(m["collision_events"], columns=["step", "time_s", "a", "b", "x", "y"])
        title = (f"{m['scenario']} · {m['controller']} · seed {m['seed']} · collisions {m['collisions']}"
                 f" · goal {'reached' if m['goal_reached'] else 'NOT reached'}")
        plot_trajectories(res.road, res.traj, out_dir / "trajectory.png", collisions=events, goals=res.goals,
                          title=title)
        plot_timeseries(series(res), out_dir / "timeseries.png", title=title)
        if res.scene.walls is not None or res.scene.obstacles:  # arena / obstacles: walls and polygons drawn
            plot_arena(res, out_dir / "arena.png", f"{m['scenario']} · seed {m['seed']} · mu {m.get('mu', 0):.3f}")
        if "plans" in res.tables:  # a path planner's log (ga_planner)
            short = f"{m['scenario']} · seed {m['seed']}"
            plot_plans(res.tables["plans"], res.tables["radar_map"], res.traj, res.scene, out_dir / "plans.png", short)
            plot_convergence(res.tables["plans"], out_dir / "convergence.png", short)
        if "formation_mode_log" in m:  # a formation: paths and kappa over time
            plot_formation(res, m, out_dir / "formation.png", f"{title} · S_ef {m.get('s_ef') or 0:.3f}")
    return m
