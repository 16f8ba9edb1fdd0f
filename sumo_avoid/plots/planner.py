"""The GA planner's figures (seed 004): every plan over the obstacles known then, and convergence.

``plans.png``: one panel per ego; the true obstacles drawn faint (the planner did not know them),
the radar map points (returns dark, their assumed shadow and face light), each plan's path
coloured by its time (early light, late dark), the driven trajectory on top. ``convergence.png``:
best fitness against generation, one line per plan (coloured by time), with the share of plans
that had a collision-free path by generation 20. Both read the plan log (``plans.csv``) and the
map table (``radar_map.csv``) the controller writes, and the recording.
"""
from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def parse_path(text: str) -> np.ndarray:
    """A logged path "x y;x y;..." -> (n, 2) m."""
    return np.array([[float(v) for v in pair.split()] for pair in text.split(";")])


def parse_fitness(text: str) -> np.ndarray:
    return np.array([float(v) for v in str(text).split(";")])


def plot_plans(plans: pd.DataFrame, radar_map: pd.DataFrame, traj: pd.DataFrame, scene, out_png: pathlib.Path,
               title: str = "") -> None:
    egos = sorted(plans["ego"].unique())
    fig = Figure(figsize=(7 * max(len(egos), 1), 7))
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(1, max(len(egos), 1)))
    cmap = colormaps["viridis_r"]
    for ax, ego in zip(axes, egos):
        if scene.walls is not None:
            w = np.vstack([scene.walls, scene.walls[:1]])
            ax.plot(w[:, 0], w[:, 1], "k-", lw=2)
        for ob in scene.obstacles:
            ax.fill(ob[:, 0], ob[:, 1], color="0.85", zorder=0)
        m = radar_map[radar_map["ego"] == ego]
        ax.plot(m.loc[~m["is_return"], "x"], m.loc[~m["is_return"], "y"], ".", color="#f4a582", ms=2, zorder=1)
        ax.plot(m.loc[m["is_return"], "x"], m.loc[m["is_return"], "y"], ".", color="#b2182b", ms=3, zorder=2,
                label="radar returns")
        mine = plans[plans["ego"] == ego]
        t_max = max(float(mine["time_s"].max()), 1e-9)
        for _, row in mine.iterrows():  # one line per plan (plotting only)
            p = parse_path(row["path"])
            ax.plot(p[:, 0], p[:, 1], "-", color=cmap(0.15 + 0.85 * row["time_s"] / t_max), lw=0.9, alpha=0.8, zorder=3)
        drv = traj[traj["id"] == ego].sort_values("step")
        ax.plot(drv["x"], drv["y"], "-", color="#d6007a", lw=2.2, zorder=4, label="driven")
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(loc="lower right", fontsize=8)
        ax.set_title(f"{title} · {ego} · {len(mine)} plans (light: early, dark: late)", fontsize=9)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110, bbox_inches="tight")


def plot_convergence(plans: pd.DataFrame, out_png: pathlib.Path, title: str = "") -> None:
    fig = Figure(figsize=(7, 4.5))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    cmap = colormaps["viridis_r"]
    t_max = max(float(plans["time_s"].max()), 1e-9) if len(plans) else 1.0
    for _, row in plans.iterrows():  # one line per plan (plotting only)
        f = parse_fitness(row["best_fitness"])
        ax.plot(np.arange(len(f)), f, "-", color=cmap(0.15 + 0.85 * row["time_s"] / t_max), lw=0.9, alpha=0.8)
        if row["generation_usable"] >= 0:
            g = int(row["generation_usable"])
            ax.plot([g], [f[g]], "o", color="k", ms=2.5)
    within = float((plans["generation_usable"].between(0, 20)).mean()) if len(plans) else float("nan")
    ax.axvline(20, color="0.5", ls=":", lw=1)
    ax.set_xlabel("generation")
    ax.set_ylabel("best fitness (usable first)")
    ax.set_title(f"{title} · {len(plans)} plans · collision-free by generation 20: {within:.0%} (dots: first)",
                 fontsize=9)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110, bbox_inches="tight")
