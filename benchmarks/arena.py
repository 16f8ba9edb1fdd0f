"""Time one flocking arena run (scenarios/arena_v4.toml: N = 100, 600 s) against the same vehicles
stepped in plain SUMO without the plug-in's computation, in the same process run.

    python benchmarks/arena.py [--agents N] [--duration S] [--repeat K] [--skip-neighbours]

``wall_s``: runner.run() (SUMO + snapshot + flocking controller + relaxation actuator + recorder);
``plain_s``: the same N vehicles spawned the same way, each step read back and moved by moveToXY
along their current velocity (no controller, no recorder); metric computation is timed apart:
``metrics`` = all of the run's metrics (outputs.run_metrics, what ``metrics.json`` holds), computed
``--repeat`` times on the same run (each time with an empty memo, so nothing is reused): the best
wall time, every wall time, and the best CPU time (process_time; on a busy machine the wall time
also counts the other processes); ``flocking metrics`` = order.flocking_metrics() alone (SPEC
§1.1-1.2 order parameters and μ), timed again on the same table after it.
Also times the controller's neighbour search, dense distance matrix vs scipy cKDTree, by N.
The line before the last: the plug-in's own cost per ego-step, (wall_s - plain_s) / (steps x N), in us
(``--agents 1000 --duration 60``: the issue's figure at 1,000 egos).
Last line: ``wall_s=X plain_s=Y ratio=Z``.
"""
from __future__ import annotations

import argparse
import dataclasses
import pathlib
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]


def plain(scn) -> float:
    from sumo_avoid.road.walls import random_positions, square
    from sumo_avoid.sumo.sim import SumoSim, sumo_args

    spec, arena = scn.spec, scn.spec.arena
    t0 = time.perf_counter()
    args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                     spec.sim.lateral_resolution_m, None, sumo_collisions=False)
    with SumoSim(args) as sim:
        rng = np.random.default_rng([spec.sim.seed, 1])
        start = random_positions(rng, arena.n_agents, square(arena.origin, arena.size_m), (),
                                 min_spacing_m=arena.min_spacing_m, margin_m=arena.margin_m)
        heading = rng.uniform(-np.pi, np.pi, arena.n_agents)
        sim.add_free_vehicles(arena.ids, start, heading, 4.0, arena.length_m, arena.width_m)
        sim.step()
        dt = sim.step_s
        for _ in range(round(spec.sim.duration_s / dt)):
            snap = sim.read()
            sim.apply(snap.ids, snap.pos + snap.vel * dt, snap.heading, snap.speed)
            sim.step()
    return time.perf_counter() - t0


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
    ap.add_argument("--repeat", type=int, default=3, help="times the metrics are computed and timed")
    ap.add_argument("--skip-neighbours", action="store_true")
    a = ap.parse_args()
    if not a.skip_neighbours:
        neighbours()
    scn = scenario.load(ROOT / "scenarios" / "arena_v4.toml",
                        [f"arena.n_agents={a.agents}", f"sim.duration_s={a.duration}"])
    t0 = time.perf_counter()
    res = runner.run(scn)
    wall = time.perf_counter() - t0
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
    p = plain(scn)
    own_us = 1e6 * (wall - p) / max(res.steps * a.agents, 1)
    print(f"plug-in's own cost (wall_s - plain_s) per ego-step: {own_us:.1f} us at {a.agents} egos, {res.steps} steps")
    print(f"wall_s={wall:.2f} plain_s={p:.2f} ratio={wall / p:.2f}")


if __name__ == "__main__":
    main()
