"""A formation run at a glance: the members' paths among the obstacles (left) and the mode kappa
over time (right, from the controller's ``formation_mode_log``), like seed 003's Fig. 4-6."""
from __future__ import annotations

import pathlib

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

#: Paths this many times longer than wide are a road: drawn with the lateral scale stretched.
STRIP = 8.0


def kappa_steps(log, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """The step function of kappa from its change log [[t, kappa], ...] (kappa 1 before the first
    change): (times, values) ready for ``step(..., where="post")``, ending at ``t_end``."""
    t = [0.0] + [float(a) for a, _ in log] + [float(t_end)]
    k = [1] + [int(b) for _, b in log]
    return np.asarray(t), np.asarray(k + k[-1:])


def plot_formation(res, m: dict, out_png: pathlib.Path, title: str = "") -> None:
    t = res.traj[res.traj["is_ego"]].sort_values(["id", "step"])
    dx, dy = float(np.ptp(t["x"])) if len(t) else 1.0, float(np.ptp(t["y"])) if len(t) else 1.0
    strip = dx > STRIP * max(dy, 1.0)  # a road: the panels one above the other, the lateral scale stretched
    fig = Figure(figsize=(14, 7.5) if strip else (12, 5.5))
    FigureCanvasAgg(fig)
    ax, axk = fig.subplots(2, 1) if strip else fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1.0]})
    for ob in res.scene.obstacles:
        ax.fill(ob[:, 0], ob[:, 1], color="0.35")
    others = res.traj[~res.traj["is_ego"]]
    if len(others):  # vehicles standing the whole run (a lane closure, parked cars), as grey boxes
        g = others.groupby("id")[["x", "y", "speed"]].agg({"x": "mean", "y": "mean", "speed": "max"})
        g = g[g["speed"] < 0.1]
        ax.plot(g["x"], g["y"], "s", color="0.4", ms=4, label="standing")
    for vid, g in t.groupby("id", sort=True):  # one line per member (plotting only)
        ax.plot(g["x"], g["y"], lw=1.2 if vid == min(t["id"]) else 0.7, label=vid)
    for step in (t["step"].min(), t["step"].max()):
        s = t[t["step"] == step]
        ax.plot(s["x"], s["y"], "k.", ms=4)
    for g in res.goals.values():
        ax.plot(*g, "rx", ms=5)
    exaggeration = max(1, int(dx / max(dy, 1.0) / STRIP)) if strip else 1
    ax.set_aspect(float(exaggeration))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)" if exaggeration == 1 else f"y (m, vertical x{exaggeration})")
    if strip:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
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
