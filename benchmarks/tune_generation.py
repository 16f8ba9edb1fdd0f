"""One generation of the formation tuner: N nests x K seeds evaluated as batch runs, on 1 and on 2
local workers, each into a fresh ledger; prints the wall time of each and the speed-up.

    python benchmarks/tune_generation.py [--nests 15] [--seeds 5] [--duration 500] [--workers 1 2]

The evaluation is the tuner's own (:class:`sumo_avoid.studies.tune.Evaluator`, the initial nests of
``--seed``), on scenarios/formation/arena_g1.toml. The speed-up needs as many idle cores as workers:
the load average before and after each batch is printed with it.
"""
from __future__ import annotations

import argparse
import os
import pathlib
import tempfile
import time

import numpy as np

from sumo_avoid.studies.cuckoo import CuckooSearch
from sumo_avoid.studies.tune import Evaluator, gains

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "formation" / "arena_g1.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nests", type=int, default=15)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--duration", type=float, default=500.0, help="sim.duration_s of each run, s")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    nests = CuckooSearch(a.nests, 2, np.random.default_rng(a.seed)).initial()
    pairs = gains(nests, (0.002, 0.2), (0.02, 2.0))
    sets = (f"sim.duration_s={a.duration}", "output.plots=false")
    walls = {}
    for w in a.workers:
        with tempfile.TemporaryDirectory(prefix="tune-bench-") as tmp:
            ev = Evaluator(SCENARIO, range(101, 101 + a.seeds), sets,
                           {"ledger": pathlib.Path(tmp) / "ledger.sqlite", "workers": w, "scheduler": None},
                           penalty=1.0, progress=False)
            load0 = os.getloadavg()[0]
            t0 = time.perf_counter()
            scores = ev(pairs)
            walls[w] = time.perf_counter() - t0
            print(f"workers {w}: {a.nests} nests x {a.seeds} seeds = {a.nests * a.seeds} runs in {walls[w]:.1f} s "
                  f"({walls[w] / (a.nests * a.seeds):.2f} s/run), best score {min(scores):.4f}; "
                  f"load average {load0:.2f} -> {os.getloadavg()[0]:.2f}", flush=True)
    if 1 in walls:
        for w, t in walls.items():
            if w != 1:
                print(f"speed-up {w} workers over 1: {walls[1] / t:.2f}x")


if __name__ == "__main__":
    main()
