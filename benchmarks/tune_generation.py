"""One generation of a tuner: its candidates x K seeds evaluated as batch runs, on 1 and on 2 local
workers, each into a fresh ledger; prints the wall time of each, the runs' summed wall time and the
speed-up.

    python benchmarks/tune_generation.py [--controller formation|flocking] [--candidates N] [--seeds K]
                                         [--duration S] [--workers 1 2]

formation: the cuckoo search's initial nests of ``--seed`` on scenarios/formation/arena_g1.toml (default 15
nests x 5 seeds, 500 s). flocking: the GA's initial population of ``--seed`` on the Table 4 arena
scenarios/arena_v4.toml (default 24 candidates x 3 seeds, 600 s, 100 vehicles). The evaluation is the
tuner's own (:class:`sumo_avoid.studies.tune.Evaluator`). The speed-up needs as many idle cores as
workers: the load average before and after each batch is printed with it.
"""
from __future__ import annotations

import argparse
import os
import pathlib
import tempfile
import time

import numpy as np

from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import ledger, tune_flocking, tune_formation
from sumo_avoid.studies.cuckoo import CuckooSearch
from sumo_avoid.studies.tune import Evaluator

ROOT = pathlib.Path(__file__).resolve().parents[1]
SETUPS = {"formation": (ROOT / "scenarios" / "formation" / "arena_g1.toml", 15, 5, 500.0),
          "flocking": (ROOT / "scenarios" / "arena_v4.toml", 24, 3, 600.0)}


def candidates(controller: str, n: int, seed: int, scn: pathlib.Path, sets) -> tuple[list, object, tuple]:
    """The first generation's candidates (override tuples), the fitness function and the ledger columns."""
    if controller == "formation":
        pairs = tune_formation.gains(CuckooSearch(n, 2, np.random.default_rng(seed)).initial(), (0.002, 0.2),
                                     (0.02, 2.0))
        return ([tune_formation.overrides(g) for g in pairs], lambda rows: tune_formation.score(rows, 1.0),
                tune_formation.COLUMNS)
    space = tune_flocking.default_bounds()
    fixed = tune_flocking.fixed_overrides(scenario.load(scn, list(sets)).controller_params["flocking"])
    x = tune_flocking.make_ga(len(space), n, seed).ask().get("X")
    return ([tune_flocking.overrides(v, space, fixed) for v in tune_flocking.values(x, space)],
            tune_flocking.fitness, ("mu",))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--controller", choices=sorted(SETUPS), default="formation")
    ap.add_argument("--candidates", "--nests", type=int, default=None)
    ap.add_argument("--seeds", type=int, default=None)
    ap.add_argument("--duration", type=float, default=None, help="sim.duration_s of each run, s")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    scn, n, k, duration = SETUPS[a.controller]
    n, k, duration = a.candidates or n, a.seeds or k, a.duration or duration
    sets = (f"sim.duration_s={duration}", "output.plots=false", *a.overrides)
    cands, value, columns = candidates(a.controller, n, a.seed, scn, sets)
    walls = {}
    for w in a.workers:
        with tempfile.TemporaryDirectory(prefix="tune-bench-") as tmp:
            led = pathlib.Path(tmp) / "ledger.sqlite"
            ev = Evaluator(scn, range(101, 101 + k), sets, {"ledger": led, "workers": w, "scheduler": None},
                           a.controller, value, columns)
            load0 = os.getloadavg()[0]
            t0 = time.perf_counter()
            scores = ev(cands)
            walls[w] = time.perf_counter() - t0
            runs_s = float(ledger.read(led)["wall_s"].sum())
            print(f"workers {w}: {n} candidates x {k} seeds = {n * k} runs in {walls[w]:.1f} s "
                  f"({walls[w] / (n * k):.2f} s/run); runs' summed wall {runs_s:.1f} s, / workers {runs_s / w:.1f} s, "
                  f"ratio {walls[w] / (runs_s / w):.2f}; scores {min(scores):.4f}..{max(scores):.4f}; "
                  f"load average {load0:.2f} -> {os.getloadavg()[0]:.2f}", flush=True)
    if 1 in walls:
        for w, t in walls.items():
            if w != 1:
                print(f"speed-up {w} workers over 1: {walls[1] / t:.2f}x")


if __name__ == "__main__":
    main()
