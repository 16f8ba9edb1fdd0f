"""One run of ``sumo-avoid reproduce table4`` (:mod:`sumo_avoid.studies.reproduce`): its job, and the
Table 4 record its child process computes from the finished rollout (the job's kind, :data:`KIND`).

A module of its own, imported by each run's child when the run ends: it imports only what the
fork server has imported already (the study's command-line side imports scipy, ~0.9 s per child).
"""
from __future__ import annotations

import pathlib

from sumo_avoid.core.output_error import vanished, writing
from sumo_avoid.metrics import basic
from sumo_avoid.metrics.flock_score import FlockingOrder
from sumo_avoid.plots.arena_plots import plot_arena
from sumo_avoid.rollout.result import RunResult
from sumo_avoid.runs.job import RunJob

ROOT = pathlib.Path(__file__).resolve().parents[2]  # the checkout: sumo_avoid/studies/ -> ../..
SPEEDS = (4, 6, 8)
# SPEC §1.3, mean and sd over the seed's 100 evaluations; phi_coll in metrics.json units (not x1e-6)
PAPER = {
    "v_vel": {4: (3.78, 0.10), 6: (5.60, 0.02), 8: (7.26, 0.02)},
    "mean_nn_dist_m": {4: (12.2, 0.4), 6: (13.4, 0.06), 8: (14.7, 0.07)},
    "phi_coll": {4: (0.94e-6, 1.3e-6), 6: (1.6e-6, 1.9e-6), 8: (1.0e-6, 1.8e-6)},
    "n_coll": {4: (1.18, 1.25), 6: (1.65, 1.34), 8: (0.89, 1.19)},
    "mu_corr": {4: (0.916, 0.015), 6: (0.923, 0.003), 8: (0.904, 0.005)},
    "mu_speed": {4: (0.938, 0.062), 6: (0.923, 0.006), 8: (0.857, 0.007)},
    "mu": {4: (0.812, 0.101), 6: (0.776, 0.086), 8: (0.728, 0.075)},
    "mu_best": {4: (0.918, None), 6: (0.873, None), 8: (0.798, None)},
}
EXTRA = ("phi_corr", "n_disc", "n_min", "phi_wall", "mu_disc", "mu_cluster", "mu_wall", "mu_coll", "collisions")

KIND = f"{__name__}:flocking_record"  # the job kind of a Table 4 run (RunJob.kind)


def table4_job(v: int, seed: int, agents: int, duration: float, sets=(), figure: str | None = None) -> RunJob:
    """The run of scenarios/arena_v{v}.toml with ``agents`` vehicles for ``duration`` s (``sets``: more
    overrides); ``figure``: draw the arena's trajectories into this PNG."""
    return RunJob(str(ROOT / "scenarios" / f"arena_v{v}.toml"), seed,
                  (f"arena.n_agents={agents}", f"sim.duration_s={float(duration)}", *sets), plots=False,
                  key=f"v{v}_s{seed}", kind=KIND, params={"v": v, "agents": agents, "duration": float(duration),
                                                          "figure": figure})


def flocking_record(res: RunResult, job: RunJob, out_dir: pathlib.Path) -> dict:
    """Table 4's record of one run, computed in the run's child: the flocking order parameters (min_gap
    and SUMO bookkeeping left out), the footprint collisions, the rollout's wall time; the figure if asked."""
    p = job.params
    m = FlockingOrder().compute(res)
    m["collisions"] = int(len(basic.collision_events(res.traj)))
    if p["figure"]:
        with writing(p["figure"], discard=True):  # a full disk, a read-only or vanished folder: one line
            if not pathlib.Path(p["figure"]).parent.is_dir():  # the study's folder vanished: not made again
                raise vanished(p["figure"])
            plot_arena(res, pathlib.Path(p["figure"]), f"v_flock = {p['v']} m/s · seed {job.seed} · "
                       f"N = {p['agents']} · {p['duration']:.0f} s · μ = {m['mu']:.3f}")
    keep = {k: m.get(k) for k in (*PAPER, *EXTRA) if k in m}
    keep.update(v=p["v"], seed=job.seed, wall_s=res.timings["total_s"])
    return keep
