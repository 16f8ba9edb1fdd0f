"""``sumo-avoid reproduce table4``: seed 000's Table 4 (SPEC §1.3) inside SUMO.

Runs scenarios/arena_v{4,6,8}.toml (Table 3 presets) over K seeds, each run in its own process
forked from the batch's fork server (:mod:`sumo_avoid.runs.worker`; libsumo allows one SUMO per
process), the run's child computing its Table 4 record (:mod:`sumo_avoid.studies.table4`), and writes to DIR:

* ``table4.csv``: ``v_flock, metric, ours_mean, ours_sd, paper_mean, paper_sd`` (one row per
  speed and per row of SPEC §1.3; metric names as in metrics.json; ``mu_best`` = best seed);
* ``table4.md``: the same side by side, with the exact command and settings;
* ``fig7_v{4,6,8}.png``: trajectories in the arena for the first seed of each speed;
* ``runs/v{V}_s{SEED}.json``: every run's metrics.
"""
from __future__ import annotations

import concurrent.futures as cf
import json
import math
import os
import pathlib
import sys
import tempfile

import numpy as np
import pandas as pd

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.core.output_error import OutputError, writing
from sumo_avoid.runs import worker
from sumo_avoid.runs.job import RunJob
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import formation_study, table3
from sumo_avoid.studies.batch import MAX_SEEDS
from sumo_avoid.studies.files import make_dirs, remove_dirs, write_atomic
from sumo_avoid.studies.table4 import EXTRA, PAPER, ROOT, SPEEDS, table4_job

class RunFailed(RuntimeError):
    """A run of the study failed (one line: which run, why)."""


def check_table4(args) -> None:
    """Every flag, and the three scenarios with the flags' values and ``--set``, before anything runs."""
    cl = "<command line>"
    for key, v, lo in (("--seeds", args.seeds, 1), ("--agents", args.agents, 1), ("--first-seed", args.first_seed, 0)):
        if v < lo:
            raise ScenarioError(cl, key, f"an integer >= {lo}", v)
    if args.first_seed + args.seeds - 1 > scenario.MAX_SEED or args.seeds > MAX_SEEDS:
        raise ScenarioError(cl, "--seeds", f"at most {MAX_SEEDS} seeds in [0, {scenario.MAX_SEED}] from --first-seed",
                            args.seeds)
    if args.jobs is not None and args.jobs < 1:
        raise ScenarioError(cl, "--jobs", "a positive integer", args.jobs)
    if not 0 < args.duration <= scenario.MAX_DURATION_S:
        raise ScenarioError(cl, "--duration", f"a duration in (0, {scenario.MAX_DURATION_S:g}] s", args.duration)
    for v in SPEEDS:
        scenario.load(ROOT / "scenarios" / f"arena_v{v}.toml", [f"arena.n_agents={args.agents}",
                      f"sim.duration_s={args.duration}", *args.overrides], seed=args.first_seed)


def summarise(runs: list[dict]) -> list[dict]:
    rows = []
    for v in SPEEDS:
        mine = [r for r in runs if r["v"] == v]
        if not mine:
            continue
        for metric, paper in PAPER.items():
            key = "mu" if metric == "mu_best" else metric
            vals = np.array([r[key] for r in mine if r.get(key) is not None], float)
            if metric == "mu_best":
                mean, sd = (float(vals.max()) if vals.size else None), None
            else:
                mean = float(vals.mean()) if vals.size else None
                sd = float(vals.std(ddof=1)) if vals.size > 1 else None
            rows.append({"v_flock": v, "metric": metric, "ours_mean": mean, "ours_sd": sd,
                         "paper_mean": paper[v][0], "paper_sd": paper[v][1]})
    return rows


def _fmt(x, metric):
    if x is None:
        return "–"
    return f"{x * 1e6:.2f}e-6" if metric == "phi_coll" else f"{x:.3f}"


def write_table(rows: list[dict], runs: list[dict], out: pathlib.Path, command: str, settings: str) -> None:
    write_atomic(out / "table4.csv", pd.DataFrame(
        rows, columns=["v_flock", "metric", "ours_mean", "ours_sd", "paper_mean", "paper_sd"]).to_csv(index=False))
    lines = ["# Table 4 (seed 000) reproduced in SUMO", "", f"Command: `{command}`", "", settings, "",
             "| v_flock | metric | ours mean ± sd | paper mean ± sd | within paper ±1 sd |", "|---|---|---|---|---|"]
    for r in rows:
        ok = ""
        if r["ours_mean"] is not None and r["paper_sd"] is not None:
            ok = "yes" if abs(r["ours_mean"] - r["paper_mean"]) <= r["paper_sd"] else "no"
        lines.append(f"| {r['v_flock']} | {r['metric']} | {_fmt(r['ours_mean'], r['metric'])} ± "
                     f"{_fmt(r['ours_sd'], r['metric'])} | {_fmt(r['paper_mean'], r['metric'])} ± "
                     f"{_fmt(r['paper_sd'], r['metric'])} | {ok} |")
    lines += ["", "Other order parameters (ours, mean over seeds):", "",
              "| v_flock | " + " | ".join(EXTRA) + " | wall s/run |", "|---" * (len(EXTRA) + 2) + "|"]
    for v in SPEEDS:
        mine = [r for r in runs if r["v"] == v]
        if mine:
            vals = [np.mean([r[k] for r in mine if r.get(k) is not None] or [np.nan]) for k in EXTRA]
            lines.append(f"| {v} | " + " | ".join(f"{x:.4g}" for x in vals)
                         + f" | {np.mean([r['wall_s'] for r in mine]):.1f} |")
    write_atomic(out / "table4.md", "\n".join(lines) + "\n")


def _outcomes(job_list: list[RunJob], jobs: int):
    """(job, outcome) as runs finish, ``jobs`` at a time, each run in its own process (the fork server);
    on an error or Ctrl-C no new run starts and the running ones are killed."""
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-table4-") as tmp, \
            cf.ThreadPoolExecutor(jobs, thread_name_prefix="sumo-avoid-table4") as ex:
        futs = {}
        for job in job_list:
            folder = pathlib.Path(tmp) / job.key
            folder.mkdir()
            futs[ex.submit(worker.run_in, folder, job, math.inf)] = job
        try:
            for fut in cf.as_completed(futs):
                yield futs[fut], fut.result()
        except BaseException:
            for f in futs:
                f.cancel()
            worker.kill_all()
            raise


def reproduce_table4(seeds: int = 20, agents: int = 100, duration: float = 600.0, out=None, jobs: int | None = None,
                     sets=(), first_seed: int = 1) -> list[dict]:
    out = pathlib.Path(out) if out else ROOT / "reports" / "table4"
    with writing(out / "runs"):
        (out / "runs").mkdir(exist_ok=True)  # in the existing ``out``: a vanished one is not made again
    job_list = [table4_job(v, s, agents, duration, sets, str(out / f"fig7_v{v}.png") if s == first_seed else None)
                for v in SPEEDS for s in range(first_seed, first_seed + seeds)]
    jobs = jobs or min(len(job_list), os.cpu_count() or 1)
    runs = []
    for job, res in _outcomes(job_list, jobs):
        if res.unwritable is not None:  # a full disk, a read-only or vanished folder
            raise OutputError(*res.unwritable)
        if not res.ok:
            raise RunFailed(f"reproduce table4: the run v_flock {job.params['v']} seed {job.seed} failed: {res.error}")
        r = res.metrics
        runs.append(r)
        write_atomic(out / "runs" / f"v{r['v']}_s{r['seed']}.json", json.dumps(r, indent=1, sort_keys=True))
        print(f"  v_flock {r['v']} seed {r['seed']}: mu {r['mu']:.3f} v_vel {r['v_vel']:.2f} "
              f"({len(runs)}/{len(job_list)}, {r['wall_s']:.0f} s)", flush=True)
    runs.sort(key=lambda r: (r["v"], r["seed"]))
    rows = summarise(runs)
    command = "sumo-avoid reproduce table4 " + " ".join(sys.argv[3:]) if len(sys.argv) > 2 else "reproduce_table4()"
    settings = (f"Settings: {seeds} seeds ({first_seed}..{first_seed + seeds - 1}), N = {agents}, {duration:.0f} s, "
                f"scenarios/arena_v{{4,6,8}}.toml" + (f", overrides {list(sets)}" if sets else ""))
    write_table(rows, runs, out, command, settings)
    return rows


def add_parser(sub) -> None:
    r = sub.add_parser("reproduce", help="reproduce a seed paper's experiment inside SUMO (table4: flocking; "
                                         "table3: the flocking GA's tuning; formation: fixed vs Lévy-tuned gains, "
                                         "docs/formation.md)")
    r.add_argument("what", choices=["table4", "table3", "formation"])
    r.add_argument("--seeds", type=int, default=20, help="seeds per speed (table3: R fresh seeds; default 20)")
    r.add_argument("--first-seed", type=int, default=1)
    r.add_argument("--agents", type=int, default=100, help="flock size N (default 100)")
    r.add_argument("--duration", type=float, default=600.0, help="run time, s (default 600)")
    r.add_argument("--jobs", type=int, default=None, help="parallel processes (default: CPU count)")
    r.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value in all runs, e.g. controllers.flocking.speed_rule=cutoff")
    r.add_argument("--out", type=pathlib.Path, default=None, help="output folder (default reports/table4, "
                                                                  "reports/table3, reports/formation)")
    f = r.add_argument_group("formation")
    f.add_argument("--tuned", type=pathlib.Path, default=ROOT / "reports" / "formation" / "tune" / "tuned.toml",
                   help="tuned.toml of sumo-avoid tune (default reports/formation/tune/tuned.toml)")
    f.add_argument("--runs", dest="seed_list", default="1-50", help="formation: seeds, e.g. 1-50 (default 1-50)")
    f.add_argument("--obstacles", type=int, default=None, help="formation: random_obstacles.count (default: the "
                                                               "scenarios' 40)")
    f.add_argument("--scenarios", nargs="*", type=pathlib.Path, default=[], help="formation: scenario files "
                                                                                 "(default the three goals)")
    f.add_argument("--workers", type=int, default=None, help="formation, table3: parallel runs (default: CPU count)")
    f.add_argument("--scheduler", default=None, metavar="ADDRESS", help="formation, table3: run on a Dask cluster")
    f.add_argument("--retry-failed", action="store_true", help="formation: re-run runs the ledger has as failed "
                                                               "(e.g. a worker killed from outside)")
    table3.add_arguments(r)
    r.set_defaults(func=_cmd)


def _cmd(args) -> int:
    if args.what == "formation":
        args.seeds, args.out = args.seed_list, args.out or ROOT / "reports" / "formation"
        return formation_study.run(args)
    if args.what == "table3":
        check_table4(args)
        return table3.run(args)
    check_table4(args)
    made = make_dirs(args.out or ROOT / "reports" / "table4", "--out")
    try:
        rows = reproduce_table4(args.seeds, args.agents, args.duration, args.out, args.jobs, args.overrides,
                                args.first_seed)
    except RunFailed as e:
        remove_dirs(made)
        print(f"sumo-avoid: error: {e}", file=sys.stderr)
        return 1
    except BaseException:
        remove_dirs([*made, (args.out or ROOT / "reports" / "table4") / "runs"])  # those still empty
        raise
    for r in rows:
        if r["metric"] in ("mu", "v_vel"):
            print(f"v_flock {r['v_flock']} {r['metric']}: ours {r['ours_mean']:.3f} paper {r['paper_mean']:.3f}")
    return 0
