"""``sumo-avoid tune formation``: Lévy-flight cuckoo search of the formation's gains (eta_at, eta_re)
(SPEC §3, seed 003) on the shared tuning engine (:mod:`sumo_avoid.studies.tune`).

Each candidate is a point of [0, 1]^2 mapped log-uniformly onto ``--eta-at`` and ``--eta-re``
ranges (printed with 6 significant digits, the form the runs and the ledger see). Its score is the
mean over the K seeds of ``s_ef + penalty x (collisions + obstacle_hits)``; a failed run scores
``FAILED_SCORE``. The cuckoo search keeps its own operators (:mod:`sumo_avoid.studies.cuckoo`).
Writes, beside the engine's ``generations.csv`` and ``convergence.png``: ``tuned.toml`` (a
``[controllers.formation]`` block to paste into a scenario) and ``history.csv`` (every candidate:
generation, phase, gains, score).
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from sumo_avoid.studies.cuckoo import CuckooSearch
from sumo_avoid.studies.files import write_atomic

FAILED_SCORE = 100.0
DEFAULT_SEEDS = 5
EXTRA_STEPS = 0
COLUMNS = ("s_ef", "collisions", "obstacle_hits")


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


def search(ev, generations: int, nests: int, seed: int, beta: float, pa: float, step: float,
           eta_at, eta_re, bar=None) -> tuple[CuckooSearch, list[dict], list[dict]]:
    """Run the search (``ev``: candidates' overrides -> scores). Returns the optimiser, the history rows
    (every candidate) and the generation rows (the nests after each generation: best, mean, worst score)."""
    cs = CuckooSearch(nests, 2, np.random.default_rng(seed), beta=beta, pa=pa, step_size=step)
    hist: list[dict] = []
    gens: list[dict] = []

    def evaluate(gen, phase, unit):
        pairs = gains(unit, eta_at, eta_re)
        scores = ev([overrides(g) for g in pairs])
        for u, g, s in zip(unit, pairs, scores):
            hist.append({"generation": gen, "phase": phase, "eta_at": g[0], "eta_re": g[1], "score": s,
                         "u_at": float(u[0]), "u_re": float(u[1])})
        return scores

    def generation_row(gen):
        (g_at, g_re), = gains(cs.best[0][None], eta_at, eta_re)
        gens.append({"generation": gen, "evaluations": cs.evaluations, "best_score": float(cs.scores.min()),
                     "mean_score": float(cs.scores.mean()), "worst_score": float(cs.scores.max()),
                     "eta_at": g_at, "eta_re": g_re})

    first = cs.initial()
    cs.tell_initial(evaluate(0, "initial", first))
    generation_row(0)
    for gen in range(1, generations + 1):
        eggs = cs.propose()
        cs.tell(eggs, evaluate(gen, "levy", eggs))
        new = cs.abandon()
        if len(new):
            cs.tell_abandoned(new, evaluate(gen, "abandon", new))
        generation_row(gen)
        if bar is not None:
            bar.set_postfix(best=f"{cs.best[1]:.4f}", refresh=False)
            bar.update(1)
    return cs, hist, gens


def add_arguments(t) -> None:
    g = t.add_argument_group("formation (Lévy-flight cuckoo search)")
    g.add_argument("--nests", type=int, default=15, help="nests N (default 15)")
    g.add_argument("--beta", type=float, default=1.5, help="Lévy tail index beta in (0, 2] (default 1.5)")
    g.add_argument("--pa", type=float, default=0.25, help="fraction of worst nests abandoned (default 0.25)")
    g.add_argument("--step", type=float, default=0.05, help="Lévy step size in the unit square (default 0.05)")
    g.add_argument("--eta-at", type=float, nargs=2, default=(0.002, 0.2), metavar=("LO", "HI"),
                   help="eta_at range, 1/s, searched log-uniformly (default 0.002 0.2)")
    g.add_argument("--eta-re", type=float, nargs=2, default=(0.02, 2.0), metavar=("LO", "HI"),
                   help="eta_re range, searched log-uniformly (default 0.02 2)")
    g.add_argument("--penalty", type=float, default=1.0, help="score added per collision or obstacle contact "
                                                              "(default 1)")


def check(args, error) -> None:
    """The formation flags (``error(key, expected, got)`` raises)."""
    if args.nests < 2:
        error("--nests", "an integer >= 2", args.nests)
    if not 0.0 < args.beta <= 2.0:
        error("--beta", "a number in (0, 2]", args.beta)
    if not 0.0 <= args.pa < 1.0:
        error("--pa", "a number in [0, 1)", args.pa)
    for key, (lo, hi) in (("--eta-at", args.eta_at), ("--eta-re", args.eta_re)):
        if not 0.0 < lo < hi:
            error(key, "0 < LO < HI", [lo, hi])
    if args.step <= 0:
        error("--step", "a positive number", args.step)


def probe(args, sets=()) -> tuple[str, ...]:
    """One candidate's overrides, to validate the scenario with before anything runs."""
    return overrides((args.eta_at[0], args.eta_re[0]))


def value_of(args):
    """The candidate's score from its runs' ledger rows (lower is better)."""
    return lambda rows: score(rows, args.penalty)


def run(args, ev, bar) -> dict:
    """Search, and write ``history.csv`` and ``tuned.toml``; returns what the engine writes and prints."""
    cs, hist, gens = search(ev, args.generations, args.nests, args.seed, args.beta, args.pa, args.step,
                            tuple(args.eta_at), tuple(args.eta_re), bar)
    best_u, best = cs.best
    (g_at, g_re), = gains(best_u[None], tuple(args.eta_at), tuple(args.eta_re))
    write_atomic(args.out / "history.csv", pd.DataFrame(hist).to_csv(index=False))
    cmd = (f"sumo-avoid tune formation {args.scenario} --generations {args.generations} --nests {args.nests} "
           f"--seeds {args.seeds} --first-seed {args.first_seed} --seed {args.seed} --beta {args.beta} --pa {args.pa}")
    write_atomic(args.out / "tuned.toml",
        f"# {cmd}\n# best score {best:.6f} (mean S_ef + {args.penalty} x contacts over seeds "
        f"{args.first_seed}-{args.first_seed + args.seeds - 1}), {cs.evaluations} candidates\n"
        f"[controllers.formation]\neta_at = {g_at!r}\neta_re = {g_re!r}\n")
    return {"history": pd.DataFrame(hist), "generations": pd.DataFrame(gens), "value": "score", "minimise": True,
            "ylabel": "score = mean S_ef + penalty x contacts",
            "title": f"cuckoo search, {args.scenario.name}: N={args.nests}, K={args.seeds}, beta={args.beta}, "
                     f"p_a={args.pa}",
            "summary": f"best eta_at {g_at} eta_re {g_re} score {best:.4f} after {args.generations} generations, "
                       f"{cs.evaluations} candidates x {args.seeds} seeds"}
