"""Time one flocking arena run (scenarios/arena_v4.toml: N = 100, 600 s) against the same vehicles
stepped in plain SUMO without the plug-in's computation, in the same process run.

    python benchmarks/arena.py [--agents N] [--duration S] [--repeat K] [--skip-neighbours] [--keep-density]
                               [--plain replay|straight]

``wall_s``: runner.run() (SUMO + snapshot + flocking controller + relaxation actuator + recorder);
``plain_s`` (default ``--plain replay``): the same N vehicles spawned the same way, then each step read
back and moved by moveToXY to the pose the plug-in's run recorded for the next step, so SUMO does the
same work on both sides (lane search in moveToXY, collision check, step: measured with cProfile,
moveToXY 0.93 / 0.89 s and simulationStep 0.35 / 0.31 s over 200 s at N = 100) and only the plug-in's
own computation differs. ``--plain straight`` (the side before 2026-11-28): each vehicle moved along its
current velocity; the flock then drifts apart and out of the arena, and SUMO's moveToXY and step cost
less than in the run (0.78 s and 0.20 s), which made the ratio look worse than the plug-in's own cost.
``--keep-density``: the arena's side grows with sqrt(N / 100), the paper's density (100 in a 250 m square);
without it N vehicles crowd the 250 m arena (1,000 there is one per 62 m^2, ~320 neighbours each within
r_c = 80 m against ~32). Metric computation is timed apart:
``metrics`` = all of the run's metrics (outputs.run_metrics, what ``metrics.json`` holds), computed
``--repeat`` times on the same run (each time with an empty memo, so nothing is reused): the best
wall time, every wall time, and the best CPU time (process_time; on a busy machine the wall time
also counts the other processes); ``flocking metrics`` = order.flocking_metrics() alone (SPEC
§1.1-1.2 order parameters and μ), timed again on the same table after it.
Also times the controller's neighbour search, dense distance matrix vs scipy cKDTree, by N.
The CPU-time line: both sides' process_time, their ratio and the own cost per ego-step from it (on these
shared VMs the wall time of identical work varies by a third between runs; CPU time much less).
The line before the last: the plug-in's own cost per ego-step, (wall_s - plain_s) / (steps x N), in us
(``--agents 1000 --duration 60 [--keep-density]``: the issue's figure at 1,000 egos).
Last line: ``wall_s=X plain_s=Y ratio=Z``.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import pathlib
import sys
import tempfile
import time

import numpy as np
from _args import positive_int  # noqa: E402  (benchmarks/_args.py: this script's folder is on sys.path)

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))  # benchmarks/radar.py's baton (--turns)


def _spawned(scn, sim) -> None:
    """The arena's vehicles, spawned as the run spawns them (same positions, headings, speed)."""
    from sumo_avoid.road.walls import random_positions, square

    spec, arena = scn.spec, scn.spec.arena
    rng = np.random.default_rng([spec.sim.seed, 1])
    start = random_positions(rng, arena.n_agents, square(arena.origin, arena.size_m), (),
                             min_spacing_m=arena.min_spacing_m, margin_m=arena.margin_m)
    heading = rng.uniform(-np.pi, np.pi, arena.n_agents)
    sim.add_free_vehicles(arena.ids, start, heading, 4.0, arena.length_m, arena.width_m)
    sim.step()


def _sim(scn):
    from sumo_avoid.sumo.sim import SumoSim, sumo_args

    spec = scn.spec
    return SumoSim(sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                             spec.sim.lateral_resolution_m, None, sumo_collisions=False))


def plain(scn) -> float:
    """``--plain straight``: each vehicle read and moved by moveToXY along its current velocity (the flock
    drifts apart and out of the arena, so SUMO's own work differs from the run's)."""
    t0, c0 = time.perf_counter(), time.process_time()
    with _sim(scn) as sim:
        _spawned(scn, sim)
        dt = sim.step_s
        for _ in range(round(scn.spec.sim.duration_s / dt)):
            snap = sim.read()
            sim.apply(snap.ids, snap.pos + snap.vel * dt, snap.heading, snap.speed)
            sim.step()
    return time.perf_counter() - t0, time.process_time() - c0


def moves_of(traj) -> list[tuple]:
    """The recorded poses, per step after the first: (ids, centres, headings, speeds)."""
    return [(tuple(g["id"]), g[["x", "y"]].to_numpy(), g["heading"].to_numpy(), g["speed"].to_numpy())
            for _, g in traj.sort_values(["step", "id"], kind="stable").groupby("step", sort=True)][1:]


def replay(scn, moves) -> tuple[float, float]:
    """Default plain side: each step every vehicle is read and moved by moveToXY to the pose the plug-in's
    run recorded for the next step (:func:`moves_of`), so SUMO does the same work as in that run (lane
    search, collision check, step) and only the plug-in's own computation is missing. (wall, CPU) s."""
    t0, c0 = time.perf_counter(), time.process_time()
    with _sim(scn) as sim:
        _spawned(scn, sim)
        for ids, pos, heading, speed in moves:
            sim.read()
            sim.apply(ids, pos, heading, speed)
            sim.step()
    return time.perf_counter() - t0, time.process_time() - c0


def turn_side(which: str, job: str, turns, profile: bool = False) -> dict:
    """One side of ``--turns`` in a child process (benchmarks/radar.py's baton): ``plugin`` runs the
    scenario again (the same run, bit for bit), ``plain`` replays its poses; both timed without the waits."""
    import pickle

    from radar import busy_s, instrumented

    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec as scenario

    with open(job, "rb") as f:
        toml, sets, moves = pickle.load(f)
    scn = scenario.load(pathlib.Path(toml), sets)
    with instrumented(turns) as t:
        if which == "plain":
            replay(scn, moves)
            steps = len(moves)
        else:
            steps = runner.run(scn).steps
    return {"busy_s": busy_s(t, turns), "sumo_step_s": t["sumo_step_s"], "turns_s": turns.turns, "steps": steps}


def paired(scn_path, sets, moves, n_agents: int, chunk: int) -> tuple[float, float]:
    """``--turns``: the run and the replay as two processes pinned to one CPU taking turns every ``chunk``
    steps (benchmarks/radar.py: both sides see the same machine within a fraction of a second)."""
    import pickle

    from radar import interleaved, paired_turns

    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    with tempfile.TemporaryDirectory() as tmp:
        job = pathlib.Path(tmp) / "job.pkl"
        job.write_bytes(pickle.dumps((str(scn_path), sets, moves)))
        cpu = max(os.sched_getaffinity(0))
        r = interleaved(job, cpu, chunk, len(moves) + 1, False, sides=("plain", "plugin"), run_side=turn_side)
    pl, pg = r["plain"], r["plugin"]
    print(paired_turns(pl["turns_s"], pg["turns_s"]))
    own = 1e6 * (pg["busy_s"] - pl["busy_s"]) / max(pg["steps"] * n_agents, 1)
    print(f"taking turns every {chunk} steps on cpu {cpu}: plug-in {pg['busy_s']:.2f} s, plain {pl['busy_s']:.2f} s, "
          f"ratio {pg['busy_s'] / pl['busy_s']:.2f}; own cost {own:.1f} us per ego-step")
    return pg["busy_s"], pl["busy_s"]


def neighbours() -> None:
    from sumo_avoid.control.flocking.terms import neighbour_pairs

    rng = np.random.default_rng(0)
    print("neighbour pairs within 80 m, density 100 per 250 m square (ms per call):")
    neighbour_pairs(np.zeros((2, 2)), np.zeros((2, 2)), 1.0, use_tree=True)  # warm-up (scipy import)
    for n in (50, 100, 200, 400, 1000, 3000):
        side = 250.0 * np.sqrt(n / 100)
        pos = rng.uniform(0, side, (n, 2))
        res = {}
        for tree in (False, True):
            reps = max(3, int(2000 / n))
            t0 = time.perf_counter()
            for _ in range(reps):
                neighbour_pairs(pos, pos, 80.0, use_tree=tree)
            res[tree] = 1e3 * (time.perf_counter() - t0) / reps
        print(f"  N={n:5d}  dense {res[False]:8.2f}  cKDTree {res[True]:8.2f}")


def main() -> None:
    from sumo_avoid.runs import outputs as evaluate
    from sumo_avoid.metrics.order import flocking_metrics
    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec as scenario

    ap = argparse.ArgumentParser()
    ap.add_argument("--agents", type=int, default=100)
    ap.add_argument("--duration", type=float, default=600.0)
    ap.add_argument("--repeat", type=positive_int, default=3, help="times the metrics are computed and timed")
    ap.add_argument("--skip-neighbours", action="store_true")
    ap.add_argument("--plain", choices=("replay", "straight"), default="replay",
                    help="plain side: replay the run's recorded poses (default; the same SUMO work) or move "
                         "each vehicle straight on (the flock drifts apart: less SUMO work than the run)")
    ap.add_argument("--turns", action="store_true",
                    help="time the run and the replay as two processes taking turns on one CPU (robust to load)")
    ap.add_argument("--chunk", type=int, default=2, help="--turns: steps per turn")
    ap.add_argument("--keep-density", action="store_true",
                    help="scale the arena's side with sqrt(N / 100): the paper's density of 100 per 250 m square")
    a = ap.parse_args()
    if not a.skip_neighbours:
        neighbours()
    sets = [f"arena.n_agents={a.agents}", f"sim.duration_s={a.duration}"]
    if a.keep_density:
        sets.append(f"arena.size_m={250.0 * (a.agents / 100) ** 0.5!r}")
    scn = scenario.load(ROOT / "scenarios" / "arena_v4.toml", sets)
    t0, c0 = time.perf_counter(), time.process_time()
    res = runner.run(scn)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    walls, cpus = [], []
    for _ in range(max(a.repeat, 1)):
        fresh = dataclasses.replace(res, _memo={})  # nothing computed before
        t1, c1 = time.perf_counter(), time.process_time()
        m = evaluate.run_metrics(fresh)
        walls.append(time.perf_counter() - t1)
        cpus.append(time.process_time() - c1)
    metrics_s = min(walls)
    print(f"arena run: N={a.agents} {a.duration:.0f} s, {res.steps} steps; loop {res.timings['loop_s']:.2f} s; "
          f"metrics {metrics_s:.2f} s (best of {len(walls)}: {' '.join(f'{w:.2f}' for w in walls)}; "
          f"CPU {min(cpus):.2f} s); mu {m['mu']:.3f}")
    prm = res.scenario.params
    t2 = time.perf_counter()
    f = flocking_metrics(res.traj, v_flock=prm.v_flock_mps, r_c_m=prm.r_c_m, phi_coll=m["phi_coll"],
                         phi_wall=m["phi_wall"])
    print(f"flocking metrics (order.flocking_metrics alone, {len(res.traj)} rows): {time.perf_counter() - t2:.2f} s "
          f"(part of the metrics {metrics_s:.2f} s); mu {f['mu']:.3f}, "
          f"{'same' if f['mu'] == m['mu'] else 'NOT the same'}")
    if a.turns:
        wall, p = paired(ROOT / "scenarios" / "arena_v4.toml", sets, moves_of(res.traj), a.agents, a.chunk)
        print(f"wall_s={wall:.2f} plain_s={p:.2f} ratio={wall / p:.2f}")
        return
    p, p_cpu = replay(scn, moves_of(res.traj)) if a.plain == "replay" else plain(scn)
    steps = max(res.steps * a.agents, 1)
    print(f"CPU time (process_time, less disturbed by other tenants than wall time): run {cpu:.2f} s, plain "
          f"{p_cpu:.2f} s, ratio {cpu / p_cpu:.2f}; own cost {1e6 * (cpu - p_cpu) / steps:.1f} us per ego-step")
    print(f"plug-in's own cost (wall_s - plain_s) per ego-step: {1e6 * (wall - p) / steps:.1f} us at {a.agents} egos, "
          f"{res.steps} steps")
    print(f"wall_s={wall:.2f} plain_s={p:.2f} ratio={wall / p:.2f}")


if __name__ == "__main__":
    main()
