"""The figures of a run, by name (:data:`PLOTS`): each entry draws its files into the run's folder
as ``draw(res, m, out_dir, title)`` (``m`` the run's metrics.json, ``title`` the run's one-line
summary). Every run gets :data:`STANDARD`; a scenario with walls or obstacles gets ``arena``; a
plug-in adds those drawn from its data by declaring them (a controller's ``plots``, like its
``metrics``): ``sumo_avoid.runs.declared.plot_names``."""
from __future__ import annotations

import pathlib

import pandas as pd

from sumo_avoid.core.registry import Registry
from sumo_avoid.metrics.series import series
from sumo_avoid.plots.arena_plots import plot_arena
from sumo_avoid.plots.formation_plots import plot_formation
from sumo_avoid.plots.planner import plot_convergence, plot_plans
from sumo_avoid.plots.trajectories import plot_timeseries, plot_trajectories


def trajectory(res, m: dict, out_dir: pathlib.Path, title: str) -> None:
    """trajectory.png: every vehicle's and person's path on the road (sidewalks, bike and bus lanes,
    crossings drawn), collisions and goals marked."""
    events = pd.DataFrame(m["collision_events"], columns=["step", "time_s", "a", "b", "x", "y"])
    plot_trajectories(res.road, res.traj, out_dir / "trajectory.png", collisions=events, goals=res.goals, title=title,
                      persons=res.persons)


def timeseries(res, m: dict, out_dir: pathlib.Path, title: str) -> None:
    """timeseries.png: the run's metrics over time, stacked."""
    plot_timeseries(series(res), out_dir / "timeseries.png", title=title)


def arena(res, m: dict, out_dir: pathlib.Path, title: str) -> None:
    """arena.png: the egos' paths among the walls and obstacles."""
    plot_arena(res, out_dir / "arena.png", f"{m['scenario']} · seed {m['seed']} · mu {m.get('mu', 0):.3f}")


def plans(res, m: dict, out_dir: pathlib.Path, title: str) -> None:
    """plans.png and convergence.png: a path planner's plans and their convergence (its plan log)."""
    short = f"{m['scenario']} · seed {m['seed']}"
    plot_plans(res.tables["plans"], res.tables["radar_map"], res.traj, res.scene, out_dir / "plans.png", short)
    plot_convergence(res.tables["plans"], out_dir / "convergence.png", short)


def formation(res, m: dict, out_dir: pathlib.Path, title: str) -> None:
    """formation.png: a formation's paths and its mode kappa over time."""
    plot_formation(res, m, out_dir / "formation.png", f"{title} · S_ef {m.get('s_ef') or 0:.3f}")


PLOTS = Registry("plot")
PLOTS.register("trajectory", trajectory)
PLOTS.register("timeseries", timeseries)
PLOTS.register("arena", arena)
PLOTS.register("plans", plans)
PLOTS.register("formation", formation)

STANDARD = ("trajectory", "timeseries")
