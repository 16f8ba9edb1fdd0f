"""Batch throughput: the same 20 short runs with 1 and with 2 local workers (target: >= 1.8x).

For each way of starting a run's process (``--start``: ``spawn`` = a fresh interpreter per run,
``fork`` = forked from the warm fork server) and each worker count, prints the throughput, the
per-run overhead (job handed over -> SUMO starts) broken down into its parts, what each run spends
after SUMO starts, and the CPU time per run in the runs and in the batch process. Fork-mode
batches are measured twice: ``cold`` (the server starts inside the timed batch, as in a fresh
``sumo-avoid batch`` command) and ``warm`` (server already running: the steady state of a long
batch). Usage:

    python benchmarks/batch.py [--runs 20] [--duration 10] [--workers 1 2] [--start spawn fork]

The speed-up needs as many idle cores as workers. The load average, and the CPU that *other*
processes and the hypervisor (steal) took while each batch ran, are printed with every batch, so a
busy machine can be recognised.
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import statistics
import tempfile
import time

from sumo_avoid.runs import worker
from sumo_avoid.runs.job import RunOutcome
from sumo_avoid.studies import batch, ledger

ROOT = pathlib.Path(__file__).resolve().parents[1]
HZ = os.sysconf("SC_CLK_TCK")
# (label, from mark, to mark): the per-run overhead, job handed over -> SUMO starts ...
OVERHEAD = [("start process", "dispatch_wall", "entry_wall"),  # fork: server wake-up + fork; spawn: interpreter
            ("imports", "entry_wall", "imported_wall"),
            ("scenario load", "imported_wall", "loaded_wall"),
            ("road+controllers", "loaded_wall", "sumo_start_wall")]
# ... and the rest of the run's wall time
AFTER = [("SUMO start+sim", "sumo_start_wall", "run_end_wall"),
         ("write outputs", "run_end_wall", "written_wall"),
         ("exit+reap", "written_wall", "reaped_wall"),
         ("parent finish", "reaped_wall", "ended_wall")]


def _cpu_jiffies() -> tuple[int, int]:
    """(busy, steal) jiffies of the whole machine from /proc/stat."""
    f = [int(x) for x in pathlib.Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    user, nice, system, _idle, _iowait, irq, softirq, steal = f[:8]
    return user + nice + system + irq + softirq, steal


def _cpu(who) -> float:
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def _phases(results: list[dict], phases) -> str:
    parts = []
    for label, a, b in phases:
        vals = [r[b] - r[a] for r in results if a in r and b in r]
        if vals:
            parts.append(f"{label} {statistics.median(vals):.3f}")
    return ", ".join(parts)


def _marks(artifacts: pathlib.Path) -> dict:
    res = RunOutcome.from_json(json.loads((artifacts / "result.json").read_text()))
    return dict(res.clock_s, cpu_s=res.cpu_s)


def measure(specs, workers: int, start: str, warm: bool) -> dict:
    if start == "fork":
        worker.shutdown()
        if warm:
            worker.prestart(wait=True)
    with tempfile.TemporaryDirectory() as tmp:
        cfg = batch.BatchConfig(tuple(specs), pathlib.Path(tmp) / "ledger.sqlite", workers=workers, start=start)
        load0, (busy0, steal0) = os.getloadavg()[0], _cpu_jiffies()
        r0s, r0c = _cpu(resource.RUSAGE_SELF), _cpu(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        counts = batch.run_batch(cfg, progress=False, log=lambda *_: None)
        wall = time.perf_counter() - t0
        cpu_parent = _cpu(resource.RUSAGE_SELF) - r0s
        busy1, steal1 = _cpu_jiffies()
        server = worker.server_info() if start == "fork" else {}
        if start == "fork" and not warm:
            worker.shutdown()  # reaped: the server's CPU (imports) and its children's land in RUSAGE_CHILDREN
        cpu_workers = _cpu(resource.RUSAGE_CHILDREN) - r0c
        df = ledger.read(cfg.ledger)
        marks = [_marks(cfg.ledger.parent / a) for a in df["artifacts"]]
    assert counts["done"] == len(specs), counts
    n = len(specs)
    ours = cpu_parent + (cpu_workers if not warm else sum(m["cpu_s"] for m in marks))
    return {"wall": wall, "rate": n / wall, "load": (load0, os.getloadavg()[0]), "server": server,
            "overhead": df["overhead_s"], "marks": marks, "cpu_parent": cpu_parent / n,
            "cpu_run": statistics.mean(m["cpu_s"] for m in marks),
            "cpu_workers": cpu_workers / n if not warm else None,
            "others": max(0.0, (busy1 - busy0) / HZ - ours) / wall, "steal": (steal1 - steal0) / HZ / wall}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--start", nargs="+", default=["spawn", "fork"], choices=worker.STARTS)
    ap.add_argument("--scenario", type=pathlib.Path, default=ROOT / "scenarios" / "overtaking.toml")
    args = ap.parse_args()
    specs = batch.expand([args.scenario], range(1, args.runs + 1),
                         [f"sim.duration_s={args.duration}", "output.plots=false"])
    print(f"{len(specs)} runs of {args.scenario.name}, {args.duration:g} s simulated each; "
          f"{os.cpu_count()} cores, load average before {os.getloadavg()[0]:.2f}")
    for start in args.start:
        print(f"\nstart={start}: " + ("forked from the warm fork server" if start == "fork"
                                      else "a fresh interpreter per run"))
        for warm in ((False, True) if start == "fork" else (False,)):
            rate = {}
            for w in args.workers:
                m = measure(specs, w, start, warm)
                rate[w] = m["rate"]
                label = ("warm " if warm else "cold ") if start == "fork" else ""
                print(f"  {label}workers {w}: {m['wall']:6.2f} s  {m['rate']:5.2f} runs/s   "
                      f"[load avg {m['load'][0]:.2f} -> {m['load'][1]:.2f}; other processes used "
                      f"{m['others']:.2f} cores, steal {m['steal']:.2f} cores]")
                oh = m["overhead"]
                print(f"      overhead (job handed over -> SUMO start) median {oh.median():.3f} s, max {oh.max():.3f} s"
                      f" = {_phases(m['marks'], OVERHEAD)}")
                print(f"      after SUMO start (median s): {_phases(m['marks'], AFTER)}")
                cpu = f"      CPU per run {m['cpu_run']:.3f} s in the run's process"
                if m["cpu_workers"] is not None:
                    cpu += f" ({m['cpu_workers']:.3f} s with process start/exit{' and server start' * (start == 'fork')})"
                print(cpu + f", {m['cpu_parent'] * 1000:.1f} ms in the batch process")
                if m["server"]:
                    print(f"      fork server: imports {m['server']['import_s']:.2f} s"
                          f"{' (inside the timed batch)' if not warm else ' (before the timed batch)'}, "
                          f"{m['server']['threads']} thread(s)")
            if len(rate) > 1:
                lo, hi = min(rate), max(rate)
                print(f"  speed-up {hi} vs {lo} workers: {rate[hi] / rate[lo]:.2f}x (target >= 1.8x for 2 vs 1)")
    print(f"\nload average after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
