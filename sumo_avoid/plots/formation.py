"""A formation run at a glance: the members' paths among the obstacles (left) and the mode kappa
over time (right, from the controller's ``formation_mode_log``), like seed 003's Fig. 4-6."""
from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def kappa_steps(log, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """The step function of kappa from its change log [[t, kappa], ...] (kappa 1 before the first
    change): (times, values) ready for ``step(..., where="post")``, ending at ``t_end``."""
    t = [0.0] + [float(a) for a, _ in log] + [float(t_end)]
    k = [1] + [int(b) for _, b in log]
    return np.asarray(t), np.asarray(k + k[-1:])


def plot_formation(res, m: dict, out_png: pathlib.Path, title: str = "") -> None:
    fig = Figure(figsize=(12, 5.5))
    FigureCanvasAgg(fig)
    ax, axk = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1.0]})
    for ob in res.scene.obstacles:
        ax.fill(ob[:, 0], ob[:, 1], color="0.35")
    t = res.traj[res.traj["is_ego"]].sort_values(["id", "step"])
    for vid, g in t.groupby("id", sort=True):  # one line per member (plotting only)
        ax.plot(g["x"], g["y"], lw=1.2 if vid == min(t["id"]) else 0.7, label=vid)
    for step in (t["step"].min(), t["step"].max()):
        s = t[t["step"] == step]
        ax.plot(s["x"], s["y"], "k.", ms=4)
    for g in res.goals.values():
        ax.plot(*g, "rx", ms=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(fontsize=7, loc="lower right")
    tk, kk = kappa_steps(m.get("formation_mode_log") or [], res.sim_time_s)
    axk.step(tk, kk, where="post", color="C3")
    axk.set_yticks([1, 2, 3], ["1 keep", "2 narrow", "3 break up"])
    axk.set_ylim(0.5, 3.5)
    axk.set_xlabel("time (s)")
    axk.set_title("mode kappa (gamma = W_max / W)", fontsize=9)
    fig.suptitle(title, fontsize=9)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110, bbox_inches="tight")
