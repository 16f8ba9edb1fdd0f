"""Plan time of the GA planner per (re)plan at the default population (issue target: median <= 20 ms,
max <= 100 ms on this machine).

    python benchmarks/planner.py [--seeds 1-5] [--repeat 3]

Runs scenarios/planner/field.toml (the radar-revealed field) for each seed with ``ga_planner``
and its default parameters, and takes every plan it made: the start (the ego's position then),
the goal, the obstacle points known then (the first ``known_points`` rows of the ego's radar map)
and the rest of the previous path (the warm start; its arc length taken as the projection of the
start, where the controller tracked it step by step). Each plan is then replayed ``repeat`` times with the same
inputs (its own generator, seeded from the seed and the plan's index) outside the simulation, and
its time is the fastest replay (the machine is shared; the fastest of a few is the least
disturbed). Prints the in-run times (as logged, with SUMO in the same process), the replays' CPU
time (``time.process_time``: what the plan costs on a core of its own, whatever else the shared
machine runs) and, last, the replays' wall time: ``plans=N median_ms=X p95_ms=Y max_ms=Z``.
"""
from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np
from _args import positive_int  # noqa: E402  (benchmarks/_args.py: this script's folder is on sys.path)

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main() -> None:
    from sumo_avoid.road.polyline import polyline_project
    from sumo_avoid.planning import ga
    from sumo_avoid.planning.pursuit import arena_bounds, rest_of
    from sumo_avoid.plots.planner import parse_path
    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec
    from sumo_avoid.studies.batch import parse_seeds

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1-5")
    ap.add_argument("--repeat", type=positive_int, default=3)
    args = ap.parse_args()
    in_run, replayed, cpu = [], [], []
    for seed in parse_seeds(args.seeds):
        scn = spec.load(ROOT / "scenarios" / "planner" / "field.toml", seed=seed)
        res = runner.run(scn)
        plans, rmap = res.tables["plans"], res.tables["radar_map"]
        p = scn.params
        bounds = arena_bounds(res.scene.walls, p.wall_margin_m)
        prev = None
        for k, row in enumerate(plans.itertuples()):
            pts = rmap[rmap["ego"] == row.ego][["x", "y"]].to_numpy()[:row.known_points]
            path = parse_path(row.path)
            best = best_cpu = np.inf
            warm = None if prev is None else rest_of(prev, polyline_project(prev, path[0]), path[0])
            for _ in range(args.repeat):
                rng = np.random.default_rng([seed, k])
                t0, c0 = time.perf_counter(), time.process_time()
                ga.plan(path[0], res.goals[row.ego], pts, p, rng, bounds, warm)
                best = min(best, 1e3 * (time.perf_counter() - t0))
                best_cpu = min(best_cpu, 1e3 * (time.process_time() - c0))
            replayed.append(best)
            cpu.append(best_cpu)
            in_run.append(row.plan_ms)
            prev = path
        print(f"seed {seed}: {len(plans)} plans, in-run median {np.median(plans['plan_ms']):.1f} ms "
              f"max {plans['plan_ms'].max():.1f} ms", flush=True)
    r, i, c = np.array(replayed), np.array(in_run), np.array(cpu)
    print(f"in-run:   plans={len(i)} median_ms={np.median(i):.1f} p95_ms={np.percentile(i, 95):.1f} max_ms={i.max():.1f}")
    print(f"cpu:      plans={len(c)} median_ms={np.median(c):.1f} p95_ms={np.percentile(c, 95):.1f} max_ms={c.max():.1f}")
    print(f"plans={len(r)} median_ms={np.median(r):.1f} p95_ms={np.percentile(r, 95):.1f} max_ms={r.max():.1f}")


if __name__ == "__main__":
    main()
