"""Batch throughput: the same 20 short runs with 1 and with 2 local workers (target: >= 1.8x).

Also prints the per-run overhead: wall time from starting the worker process to SUMO's first
step (interpreter start, imports, scenario load, SUMO start). Usage:

    python benchmarks/batch.py [--runs 20] [--duration 10] [--workers 1 2]

The speed-up needs as many idle cores as workers; the load average is printed so a busy machine
can be recognised.
"""
from __future__ import annotations

import argparse
import os
import pathlib
import resource
import tempfile
import time

from sumo_avoid import batch, ledger

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--scenario", type=pathlib.Path, default=ROOT / "scenarios" / "overtaking.toml")
    args = ap.parse_args()
    specs = batch.expand([args.scenario], range(1, args.runs + 1),
                         [f"sim.duration_s={args.duration}", "output.plots=false"])
    print(f"{len(specs)} runs of {args.scenario.name}, {args.duration:g} s simulated each; "
          f"{os.cpu_count()} cores, load average before {os.getloadavg()[0]:.2f}")
    rate = {}
    for w in args.workers:
        with tempfile.TemporaryDirectory() as tmp:
            cfg = batch.BatchConfig(tuple(specs), pathlib.Path(tmp) / "ledger.sqlite", workers=w)
            r0s, r0c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            counts = batch.run_batch(cfg, progress=False, log=lambda *_: None)
            wall = time.perf_counter() - t0
            r1s, r1c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu_parent = (r1s.ru_utime + r1s.ru_stime) - (r0s.ru_utime + r0s.ru_stime)
            cpu_runs = (r1c.ru_utime + r1c.ru_stime) - (r0c.ru_utime + r0c.ru_stime)
            df = ledger.read(cfg.ledger)
        assert counts["done"] == len(specs), counts
        rate[w] = len(specs) / wall
        oh = df["overhead_s"]
        print(f"workers {w}: {wall:6.1f} s  {rate[w]:.2f} runs/s  per-run wall {df['wall_s'].mean():.2f} s  "
              f"overhead (process start -> first step) median {oh.median():.2f} s, max {oh.max():.2f} s\n"
              f"           CPU per run {cpu_runs / len(specs):.2f} s in workers, {cpu_parent / len(specs) * 1000:.0f} ms "
              f"in the batch process; cores used on average {(cpu_runs + cpu_parent) / wall:.2f}")
    if len(rate) > 1:
        lo, hi = min(rate), max(rate)
        print(f"speed-up {hi} vs {lo} workers: {rate[hi] / rate[lo]:.2f}x (target >= 1.8x for 2 vs 1); "
              f"load average after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
