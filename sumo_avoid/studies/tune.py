"""``sumo-avoid tune formation SCENARIO``: Lévy-flight cuckoo search of the formation's gains
(eta_at, eta_re) (SPEC §3, seed 003), every evaluation a batch run.

Each candidate is a point of [0, 1]^2 mapped log-uniformly onto ``--eta-at`` and ``--eta-re``
ranges (printed with 6 significant digits, the form the runs and the ledger see). Its score is the
mean over the K seeds ``--first-seed`` .. ``--first-seed + K - 1`` (the same seeds for every
candidate) of ``s_ef + penalty x (collisions + obstacle_hits)``; a failed run scores
``FAILED_SCORE``. The runs of a generation go to :func:`sumo_avoid.studies.batch.run_batch` as one
batch (process-isolated, the SQLite ledger, local workers or a Dask scheduler), so a tuner killed at
any point resumes by re-running the same command: the search's random stream (``--seed``) replays
the same candidates and the ledger supplies every finished run. Writes to ``--out``:
``tuned.toml`` (a ``[controllers.formation]`` block to paste into a scenario), ``history.csv``
(every candidate: generation, phase, gains, score) and ``convergence.png``.
"""
from __future__ import annotations

import io
import math
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
from sumo_avoid.studies.cuckoo import CuckooSearch
from sumo_avoid.studies.files import check_out_file, make_dirs, remove_dirs, write_atomic

FAILED_SCORE = 100.0
TUNABLE = ("formation",)


def gains(unit: np.ndarray, eta_at: tuple[float, float], eta_re: tuple[float, float]) -> list[tuple[float, float]]:
    """Unit-cube points (n, 2) -> (eta_at, eta_re) pairs, log-uniform in the ranges, 6 significant digits."""
    out = []
    for a, r in np.asarray(unit, float).reshape(-1, 2):
        ga = 10 ** (math.log10(eta_at[0]) + a * (math.log10(eta_at[1]) - math.log10(eta_at[0])))
        gr = 10 ** (math.log10(eta_re[0]) + r * (math.log10(eta_re[1]) - math.log10(eta_re[0])))
        out.append((float(f"{ga:.6g}"), float(f"{gr:.6g}")))
    return out


def overrides(g: tuple[float, float]) -> tuple[str, ...]:
    return (f"controllers.formation.eta_at={g[0]!r}", f"controllers.formation.eta_re={g[1]!r}")


def score(rows: pd.DataFrame, penalty: float) -> float:
    """Mean over the runs of s_ef + penalty (collisions + obstacle_hits); a failed run FAILED_SCORE."""
    vals = []
    for r in rows.itertuples():
        if r.status != "done" or r.s_ef is None or pd.isna(r.s_ef):
            vals.append(FAILED_SCORE)
        else:
            vals.append(float(r.s_ef) + penalty * (float(r.collisions) + float(r.obstacle_hits)))
    return float(np.mean(vals))


class Evaluator:
    """Scores candidate gain pairs through batch runs into one ledger."""

    def __init__(self, scenario, seeds, sets, cfg: dict, penalty: float, progress: bool):
        self.scenario, self.seeds, self.sets, self.cfg = scenario, tuple(seeds), tuple(sets), cfg
        self.penalty, self.progress = penalty, progress

    def __call__(self, pairs) -> list[float]:
        plans = [[batch.plan(self.scenario, s, self.sets + overrides(g), "formation") for s in self.seeds]
                 for g in pairs]
        runs = tuple({p.key: p for row in plans for p in row}.values())
        cfg = batch.BatchConfig(runs, **self.cfg)
        batch.run_batch(cfg, progress=self.progress, log=lambda *a: None)
        df = ledger_mod.read(cfg.ledger).set_index("key")
        for col in ("s_ef", "collisions", "obstacle_hits"):
            if col not in df:
                df[col] = np.nan
        return [score(df.loc[[p.key for p in row]], self.penalty) for row in plans]


def tune(ev: Evaluator, generations: int, nests: int, seed: int, beta: float, pa: float, step: float,
         eta_at, eta_re, bar=None) -> tuple[CuckooSearch, list[dict]]:
    """Run the search; returns the optimiser and the history rows."""
    cs = CuckooSearch(nests, 2, np.random.default_rng(seed), beta=beta, pa=pa, step_size=step)
    hist: list[dict] = []

    def record(gen, phase, unit, scores):
        for u, g, s in zip(unit, gains(unit, eta_at, eta_re), scores):
            hist.append({"generation": gen, "phase": phase, "eta_at": g[0], "eta_re": g[1], "score": s,
                         "u_at": float(u[0]), "u_re": float(u[1])})

    first = cs.initial()
    sc = ev(gains(first, eta_at, eta_re))
    cs.tell_initial(sc)
    record(0, "initial", first, sc)
    for gen in range(1, generations + 1):
        eggs = cs.propose()
        sc = ev(gains(eggs, eta_at, eta_re))
        cs.tell(eggs, sc)
        record(gen, "levy", eggs, sc)
        new = cs.abandon()
        if len(new):
            sc = ev(gains(new, eta_at, eta_re))
            cs.tell_abandoned(new, sc)
            record(gen, "abandon", new, sc)
        if bar is not None:
            bar.set_postfix(best=f"{cs.best[1]:.4f}", refresh=False)
            bar.update(1)
    return cs, hist


def plot_convergence(hist: pd.DataFrame, out_png: pathlib.Path, title: str) -> None:
    fig = Figure(figsize=(7, 4))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ok = hist["score"] < FAILED_SCORE
    ax.scatter(hist["generation"][ok], hist["score"][ok], s=8, c="0.6", label="candidates")
    best = hist.groupby("generation")["score"].min().cummin()
    ax.plot(best.index, best.to_numpy(), "b-o", ms=4, label="best so far")
    ax.set_xlabel("generation")
    ax.set_ylabel("score = mean S_ef + penalty x contacts")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    write_atomic(out_png, buf.getvalue())


def add_parser(sub) -> None:
    t = sub.add_parser("tune", help="Lévy-flight cuckoo search of a controller's gains (formation: eta_at, eta_re)")
    t.add_argument("controller", help="the controller to tune: formation")
    t.add_argument("scenario", type=pathlib.Path)
    t.add_argument("--generations", type=int, default=10, help="generations G (default 10)")
    t.add_argument("--nests", type=int, default=15, help="nests N (default 15)")
    t.add_argument("--seeds", type=int, default=5, help="K scenario seeds per candidate (default 5)")
    t.add_argument("--first-seed", type=int, default=101, help="the K seeds start here (default 101)")
    t.add_argument("--seed", type=int, default=1, help="the search's own random seed (default 1)")
    t.add_argument("--beta", type=float, default=1.5, help="Lévy tail index beta in (0, 2] (default 1.5)")
    t.add_argument("--pa", type=float, default=0.25, help="fraction of worst nests abandoned (default 0.25)")
    t.add_argument("--step", type=float, default=0.05, help="Lévy step size in the unit square (default 0.05)")
    t.add_argument("--eta-at", type=float, nargs=2, default=(0.002, 0.2), metavar=("LO", "HI"),
                   help="eta_at range, 1/s, searched log-uniformly (default 0.002 0.2)")
    t.add_argument("--eta-re", type=float, nargs=2, default=(0.02, 2.0), metavar=("LO", "HI"),
                   help="eta_re range, searched log-uniformly (default 0.02 2)")
    t.add_argument("--penalty", type=float, default=1.0, help="score added per collision or obstacle contact (default 1)")
    t.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    t.add_argument("--workers", type=int, default=None, help="parallel runs (default: number of cores)")
    t.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on a Dask cluster")
    t.add_argument("--ledger", type=pathlib.Path, default=None, help="SQLite ledger (default OUT/ledger.sqlite)")
    t.add_argument("--out", type=pathlib.Path, default=pathlib.Path("reports/tune"), help="output folder")
    t.add_argument("--quiet", action="store_true", help="no progress bars")
    t.set_defaults(func=cmd_tune)


def _check(args) -> None:
    cl = "<command line>"
    if args.controller not in TUNABLE:
        raise ScenarioError(cl, "controller", f"one of {list(TUNABLE)}", args.controller)
    for key, v, lo in (("--generations", args.generations, 0), ("--nests", args.nests, 2), ("--seeds", args.seeds, 1),
                       ("--first-seed", args.first_seed, 0)):
        if v < lo:
            raise ScenarioError(cl, key, f"an integer >= {lo}", v)
    batch.workers_or_cores(args.workers)
    if not 0.0 < args.beta <= 2.0:
        raise ScenarioError(cl, "--beta", "a number in (0, 2]", args.beta)
    if not 0.0 <= args.pa < 1.0:
        raise ScenarioError(cl, "--pa", "a number in [0, 1)", args.pa)
    for key, (lo, hi) in (("--eta-at", args.eta_at), ("--eta-re", args.eta_re)):
        if not 0.0 < lo < hi:
            raise ScenarioError(cl, key, "0 < LO < HI", [lo, hi])
    if args.step <= 0:
        raise ScenarioError(cl, "--step", "a positive number", args.step)


def cmd_tune(args) -> int:
    _check(args)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    sets = tuple(args.overrides) + ("output.plots=false",)
    for s in seeds:  # bad scenario or --set: one line, exit 2, nothing written
        batch.plan(args.scenario, s, sets + overrides((args.eta_at[0], args.eta_re[0])), "formation")
    led = args.ledger or args.out / "ledger.sqlite"
    check_out_file(args.out / "tuned.toml", "--out")  # refused now, not after the search
    ledger_mod.check(led, "--ledger")
    cfg = {"ledger": led, "workers": batch.workers_or_cores(args.workers), "scheduler": args.scheduler}
    show = not args.quiet and sys.stderr.isatty()
    ev = Evaluator(args.scenario, seeds, sets, cfg, args.penalty, progress=False)
    t0 = time.perf_counter()
    made = make_dirs(args.out, "--out")  # now: a folder that vanishes during the search is not made again
    try:
        with tqdm(total=args.generations, unit="gen", disable=not show, file=sys.stderr) as bar:
            cs, hist = tune(ev, args.generations, args.nests, args.seed, args.beta, args.pa, args.step,
                            tuple(args.eta_at), tuple(args.eta_re), bar)
    except KeyboardInterrupt:
        print("tune: interrupted; running runs killed; re-run the same command to resume", file=sys.stderr)
        return 130
    except BaseException:
        remove_dirs(made)
        raise
    best_u, best = cs.best
    (g_at, g_re), = gains(best_u[None], tuple(args.eta_at), tuple(args.eta_re))
    df = pd.DataFrame(hist)
    write_atomic(args.out / "history.csv", df.to_csv(index=False))
    cmd = (f"sumo-avoid tune formation {args.scenario} --generations {args.generations} --nests {args.nests} "
           f"--seeds {args.seeds} --first-seed {args.first_seed} --seed {args.seed} --beta {args.beta} --pa {args.pa}")
    write_atomic(args.out / "tuned.toml",
                 f"# {cmd}\n# best score {best:.6f} (mean S_ef + {args.penalty} x contacts over seeds "
                 f"{args.first_seed}-{args.first_seed + args.seeds - 1}), {cs.evaluations} candidates\n"
                 f"[controllers.formation]\neta_at = {g_at!r}\neta_re = {g_re!r}\n")
    plot_convergence(df, args.out / "convergence.png", f"cuckoo search, {args.scenario.name}: N={args.nests}, "
                     f"K={args.seeds}, beta={args.beta}, p_a={args.pa}")
    print(f"tune: best eta_at {g_at} eta_re {g_re} score {best:.4f} after {args.generations} generations, "
          f"{cs.evaluations} candidates x {args.seeds} seeds ({time.perf_counter() - t0:.1f} s) -> {args.out}/tuned.toml")
    return 0
