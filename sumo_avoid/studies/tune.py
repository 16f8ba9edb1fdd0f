"""``sumo-avoid tune CONTROLLER SCENARIO``: the tuning engine shared by every tunable controller.

A method per controller searches its parameters (formation: seed 003's Lévy-flight cuckoo search,
:mod:`sumo_avoid.studies.tune_formation`; flocking: seed 000's genetic algorithm from pymoo,
:mod:`sumo_avoid.studies.tune_flocking_cli`); the engine evaluates its candidates, keeps the ledger and
writes the shared outputs. A candidate is a tuple of ``--set`` overrides; it is scored over the K
seeds ``--first-seed`` .. ``--first-seed + K - 1`` (the same seeds for every candidate). The runs of
a generation go to :func:`sumo_avoid.studies.batch.run_batch` as one batch (process-isolated, the
SQLite ledger, local workers or a Dask scheduler), so a tuner killed at any point resumes by re-running
the same command: the search's random stream (``--seed``) replays the same candidates and the ledger
supplies every finished run. Writes to ``--out``: ``generations.csv`` (per generation the best, mean
and worst value of the method's population and its best parameters), ``convergence.png``, and the
method's own files (``tuned.toml`` among them).
"""
from __future__ import annotations

import io
import pathlib
import sys
import time

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from tqdm import tqdm

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.studies import batch
from sumo_avoid.studies import ledger as ledger_mod
from sumo_avoid.studies import tune_flocking_cli, tune_formation
from sumo_avoid.studies.files import check_out_file, make_dirs, remove_dirs, write_atomic

METHODS = {"formation": tune_formation, "flocking": tune_flocking_cli}
TUNABLE = tuple(METHODS)
CL = "<command line>"


class Evaluator:
    """Scores candidates (each a tuple of overrides) through batch runs into one ledger: ``value`` maps a
    candidate's ledger rows (one per seed, in seed order) to its score; ``columns``: metric columns it
    reads (NaN where no run wrote them)."""

    def __init__(self, scenario, seeds, sets, cfg: dict, controller: str, value, columns=(), progress=False):
        self.scenario, self.seeds, self.sets, self.cfg = scenario, tuple(seeds), tuple(sets), cfg
        self.controller, self.value, self.columns, self.progress = controller, value, tuple(columns), progress

    def with_seeds(self, seeds) -> Evaluator:
        return Evaluator(self.scenario, seeds, self.sets, self.cfg, self.controller, self.value, self.columns,
                         self.progress)

    def rows(self, cands) -> list[pd.DataFrame]:
        """Run every candidate on every seed (runs in the ledger are not re-run); their ledger rows."""
        plans = [[batch.plan(self.scenario, s, self.sets + tuple(c), self.controller) for s in self.seeds]
                 for c in cands]
        runs = tuple({p.key: p for row in plans for p in row}.values())
        cfg = batch.BatchConfig(runs, **self.cfg)
        batch.run_batch(cfg, progress=self.progress, log=lambda *a: None)
        df = ledger_mod.read(cfg.ledger).set_index("key")
        for col in self.columns:
            if col not in df:
                df[col] = np.nan
        return [df.loc[[p.key for p in row]] for row in plans]

    def __call__(self, cands) -> list[float]:
        return [self.value(r) for r in self.rows(cands)]


def plot_convergence(hist: pd.DataFrame, gens: pd.DataFrame, value: str, minimise: bool, out_png: pathlib.Path,
                     title: str, ylabel: str) -> None:
    """Every candidate's value by generation, and the population's best, mean and worst."""
    fig = Figure(figsize=(7, 4))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ok = np.isfinite(hist[value]) & ((hist[value] < tune_formation.FAILED_SCORE) if minimise else True)
    ax.scatter(hist["generation"][ok], hist[value][ok], s=8, c="0.6", label="candidates")
    for col, style, label in (("best", "b-o", "population best"), ("mean", "g--", "population mean"),
                              ("worst", "r:", "population worst")):
        ax.plot(gens["generation"], gens[f"{col}_{value}"], style, ms=4, label=label)
    ax.set_xlabel("generation")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    write_atomic(out_png, buf.getvalue())


def add_parser(sub) -> None:
    t = sub.add_parser("tune", help="tune a controller's parameters (formation: Lévy-flight cuckoo search of eta_at, "
                                    "eta_re; flocking: genetic algorithm over its 11 parameters)")
    t.add_argument("controller", help=f"the controller to tune: {' or '.join(TUNABLE)}")
    t.add_argument("scenario", type=pathlib.Path)
    t.add_argument("--generations", type=int, default=10, help="generations G (default 10)")
    t.add_argument("--seeds", type=int, default=None, help="K scenario seeds per candidate (default 5 formation, "
                                                           "3 flocking)")
    t.add_argument("--first-seed", type=int, default=101, help="the K seeds start here (default 101)")
    t.add_argument("--seed", type=int, default=1, help="the search's own random seed (default 1)")
    t.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    t.add_argument("--workers", type=int, default=None, help="parallel runs (default: number of cores)")
    t.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on a Dask cluster")
    t.add_argument("--ledger", type=pathlib.Path, default=None, help="SQLite ledger (default OUT/ledger.sqlite)")
    t.add_argument("--out", type=pathlib.Path, default=pathlib.Path("reports/tune"), help="output folder")
    t.add_argument("--quiet", action="store_true", help="no progress bars")
    for method in METHODS.values():
        method.add_arguments(t)
    t.set_defaults(func=cmd_tune)


def _error(key, expected, got):
    raise ScenarioError(CL, key, expected, got)


def check(args):
    """Every flag (one line, exit 2); the controller's method."""
    if args.controller not in METHODS:
        _error("controller", f"one of {list(TUNABLE)}", args.controller)
    method = METHODS[args.controller]
    if args.seeds is None:
        args.seeds = method.DEFAULT_SEEDS
    for key, v, lo in (("--generations", args.generations, 0), ("--seeds", args.seeds, 1),
                       ("--first-seed", args.first_seed, 0)):
        if v < lo:
            _error(key, f"an integer >= {lo}", v)
    batch.workers_or_cores(args.workers)
    method.check(args, _error)
    return method


def prepare(args):
    """Every check before anything runs or is written (bad input: ScenarioError); the method and its evaluator."""
    method = check(args)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    sets = tuple(args.overrides) + ("output.plots=false",)
    probe = method.probe(args, sets)  # bad scenario, --set or bound: one line, exit 2, nothing written
    for s in seeds:
        batch.plan(args.scenario, s, sets + probe, args.controller)
    led = args.ledger or args.out / "ledger.sqlite"
    check_out_file(args.out / "tuned.toml", "--out")  # refused now, not after the search
    ledger_mod.check(led, "--ledger")
    cfg = {"ledger": led, "workers": batch.workers_or_cores(args.workers), "scheduler": args.scheduler}
    return method, Evaluator(args.scenario, seeds, sets, cfg, args.controller, method.value_of(args), method.COLUMNS)


def execute(args, method, ev) -> dict:
    """The search and the shared outputs; returns the method's result (``generations``, ``history``, ...)."""
    show = not args.quiet and sys.stderr.isatty()
    t0 = time.perf_counter()
    made = make_dirs(args.out, "--out")  # now: a folder that vanishes during the search is not made again
    try:
        with tqdm(total=args.generations + method.EXTRA_STEPS, unit="gen", disable=not show, file=sys.stderr) as bar:
            res = method.run(args, ev, bar)
        gens = res["generations"]
        write_atomic(args.out / "generations.csv", gens.to_csv(index=False))
        plot_convergence(res["history"], gens, res["value"], res["minimise"], args.out / "convergence.png",
                         res["title"], res["ylabel"])
    except BaseException:
        remove_dirs(made)
        raise
    print(f"tune: {res['summary']} ({time.perf_counter() - t0:.1f} s) -> {args.out}/tuned.toml")
    return res


def cmd_tune(args) -> int:
    method, ev = prepare(args)
    try:
        execute(args, method, ev)
    except KeyboardInterrupt:
        print("tune: interrupted; running runs killed; re-run the same command to resume", file=sys.stderr)
        return 130
    return 0
