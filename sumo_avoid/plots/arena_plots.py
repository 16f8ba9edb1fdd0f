"""The flock's trajectories in the arena (like seed 000's Fig. 7), walls and obstacles drawn."""
from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def plot_arena(res, out_png: pathlib.Path, title: str = "") -> None:
    """Trajectories of every ego in the arena (like the seed's Fig. 7), walls and obstacles drawn."""
    fig = Figure(figsize=(7, 7))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    if res.scene.walls is not None:
        w = np.vstack([res.scene.walls, res.scene.walls[:1]])
        ax.plot(w[:, 0], w[:, 1], "k-", lw=2)
    for ob in res.scene.obstacles:
        ax.fill(ob[:, 0], ob[:, 1], color="0.35")
    t = res.traj[res.traj["is_ego"]].sort_values(["id", "step"])
    for _, g in t.groupby("id", sort=True):  # one line per vehicle (plotting only)
        ax.plot(g["x"], g["y"], lw=0.4, alpha=0.6)
    last = t[t["step"] == t["step"].max()]
    ax.plot(last["x"], last["y"], "k.", ms=3)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title, fontsize=9)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110, bbox_inches="tight")
