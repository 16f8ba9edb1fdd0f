"""The flocking method of ``sumo-avoid tune`` (:mod:`sumo_avoid.studies.tune`): its flags, the GA search
(:mod:`sumo_avoid.studies.tune_flocking`), then the seed's statistics (:mod:`sumo_avoid.studies.tune_stats`):
the best candidate and the scenario's own parameters each evaluated on ``--evals`` R seeds from
``--eval-first-seed`` (seeds the tuner never saw; every run in the same ledger). Writes ``tuned.toml``
(a ``[controllers.flocking]`` table to paste into a scenario), ``history.csv`` (every candidate),
``evaluations.csv`` (the fresh runs per seed), ``statistics.json`` and ``statistics.md``. With
``--start-from scenario`` generation 0's first individual is the scenario's own parameters (a warm start,
:class:`sumo_avoid.studies.tune_flocking.WarmStart`); the recorded command then names the flag.
"""
from __future__ import annotations

import math
import pathlib
import sys

import pandas as pd

from sumo_avoid.control.flocking.terms import FlockingParams
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import tune_flocking as ga
from sumo_avoid.studies import tune_stats
from sumo_avoid.studies.files import write_atomic

DEFAULT_SEEDS = 3
EXTRA_STEPS = 2  # the initial population, the fresh evaluations
COLUMNS = tune_stats.METRICS


def add_arguments(t) -> None:
    g = t.add_argument_group("flocking (genetic algorithm, pymoo)")
    g.add_argument("--pop-size", type=int, default=24, help="population (and offspring per generation; default 24)")
    g.add_argument("--bound", nargs=3, action="append", default=[], metavar=("NAME", "LO", "HI"),
                   help="search NAME (a [controllers.flocking] key, e.g. r0_rep_m) in [LO, HI]; log-uniformly "
                        "where HI/LO >= 10 (default: the scenario's [tune.flocking], else Table 3's ranges widened)")
    g.add_argument("--evals", type=int, default=20, help="R fresh evaluations of the best candidate (and of the "
                                                         "scenario's parameters) on unseen seeds (default 20)")
    g.add_argument("--eval-first-seed", type=int, default=1, help="the R fresh seeds start here (default 1)")
    g.add_argument("--start-from", default="random", metavar="random|scenario",
                   help="generation 0: all random (default), or 'scenario': a warm start, the scenario's own "
                        "[controllers.flocking] values (the arena_v* scenarios: the paper's Table 3 optimum) as one "
                        "individual (a value outside its bound clipped, said on stderr), the rest random as without "
                        "it: can the GA improve on them?")


def _bound_triples(args, error) -> list:
    out = []
    for name, lo, hi in args.bound:
        try:
            out.append((name, float(lo), float(hi)))
        except ValueError:
            error("--bound", "NAME LO HI with numbers LO < HI", [name, lo, hi])
    return out


def check(args, error) -> None:
    if args.pop_size < 2:
        error("--pop-size", "an integer >= 2", args.pop_size)
    if args.evals < 2:
        error("--evals", "an integer >= 2 (a mean and an sd)", args.evals)
    if args.eval_first_seed < 0 or args.eval_first_seed + args.evals - 1 > scenario.MAX_SEED:
        error("--eval-first-seed", f"R seeds in [0, {scenario.MAX_SEED}]", args.eval_first_seed)
    tuning = range(args.first_seed, args.first_seed + args.seeds)
    fresh = range(args.eval_first_seed, args.eval_first_seed + args.evals)
    if tuning.start < fresh.stop and fresh.start < tuning.stop:
        error("--eval-first-seed", f"fresh seeds the tuner never saw (it tunes on {tuning.start}.."
                                   f"{tuning.stop - 1})", f"{fresh.start}..{fresh.stop - 1}")
    _bound_triples(args, error)
    if args.start_from not in ga.START_FROM:
        error("--start-from", " or ".join(ga.START_FROM), args.start_from)


def space_of(args, sets) -> tuple[tuple[ga.Bound, ...], tuple[str, ...], FlockingParams]:
    """The search space, the fixed overrides and the scenario's flocking parameters (scenario loaded with
    ``sets``; raises ScenarioError)."""
    scn = scenario.load(args.scenario, list(sets), controller="flocking", seed=args.first_seed)
    space = ga.bounds(_bound_triples(args, None), scn.spec.tune.get("flocking", {}), str(args.scenario))
    params = scn.controller_params["flocking"]
    return space, ga.fixed_overrides(params), params


def probe(args, sets) -> tuple[str, ...]:
    space, fixed, _ = space_of(args, sets)
    return ga.overrides(ga.values([[0.5] * len(space)], space)[0], space, fixed)


def value_of(args):
    return ga.fitness


def shown(path) -> str:
    """A path as a command line would give it here: relative to the working folder when under it."""
    p = pathlib.Path(path)
    try:
        return str(p.resolve().relative_to(pathlib.Path.cwd()))
    except ValueError:
        return str(p)


def command(args) -> str:
    extra = "".join(f" --bound {n} {lo} {hi}" for n, lo, hi in args.bound)
    extra += "".join(f" --set {s}" for s in args.overrides)
    extra += "" if args.start_from == "random" else f" --start-from {args.start_from}"  # the default as before
    return (f"sumo-avoid tune flocking {shown(args.scenario)} --generations {args.generations} "
            f"--pop-size {args.pop_size} "
            f"--seeds {args.seeds} --first-seed {args.first_seed} --seed {args.seed} --evals {args.evals} "
            f"--eval-first-seed {args.eval_first_seed}{extra}")


def tuned_toml(best: dict, names, head: str, params) -> str:
    lines = [head, "[controllers.flocking]", 'preset = ""', f"v_flock_mps = {params.v_flock_mps!r}",
             f"v_max_mps = {params.v_max_mps!r}"]
    lines += [f"{n} = {best[n]!r}" for n in names]
    return "\n".join(lines) + "\n"


def run(args, ev, bar) -> dict:
    sets = ev.sets
    space, fixed, params = space_of(args, sets)
    names = [b.name for b in space]
    warm = ga.warm_start(params, space) if args.start_from == "scenario" else None
    if warm is not None and warm.clipped:
        bar.write(f"tune: --start-from scenario: {warm.note()}", file=sys.stderr)
    hist, gens = ga.search(ev, space, fixed, args.generations, args.pop_size, args.seed, bar, warm)
    hist = pd.DataFrame(hist)
    top = ga.best_of(hist)
    best = {n: float(top[n]) for n in names}
    fresh = ev.with_seeds(range(args.eval_first_seed, args.eval_first_seed + args.evals))
    cand = ga.overrides([best[n] for n in names], space, fixed)
    tuned_rows, base_rows = fresh.rows([cand, ()])
    bar.update(1)
    evals = tune_stats.per_seed(tuned_rows, "tuned").merge(tune_stats.per_seed(base_rows, "baseline"), on="seed")
    stats = tune_stats.statistics(hist, names, {**best, "fitness": float(top["mu"])}, evals)
    write_atomic(args.out / "history.csv", hist.to_csv(index=False))
    write_atomic(args.out / "evaluations.csv", evals.to_csv(index=False))
    cmd = command(args)
    tune_stats.write(stats, args.out, cmd, "the scenario's parameters")
    p = scenario.load(args.scenario, list(sets), seed=args.first_seed).controller_params["flocking"]
    head = (f"# {cmd}\n# best fitness {top['mu']:.6f} (mean mu over seeds {args.first_seed}-"
            f"{args.first_seed + args.seeds - 1}), {len(hist)} candidates; on {args.evals} fresh seeds mu_max "
            f"{stats['mu_max']:.4f}, mean {stats['mu_mean']:.4f} +- {stats['mu_sd']:.4f}\n"
            "# v_flock_mps and v_max_mps as in the scenario; its preset cleared (a preset replaces keys at their "
            "default)")
    write_atomic(args.out / "tuned.toml", tuned_toml(best, names, head, p))
    print(f"tune: on {args.evals} fresh seeds mu {stats['mu_mean']:.4f} +- {stats['mu_sd']:.4f} (max "
          f"{stats['mu_max']:.4f}); the scenario's parameters {stats['baseline']['mu_mean']:.4f}; N(mu >= mean) "
          f"{stats['n_above_mean']}")
    return {"history": hist, "generations": pd.DataFrame(gens), "value": "mu", "minimise": False,
            "ylabel": "mu (mean over the K tuning seeds)",
            "title": f"GA, {args.scenario.name}: population {args.pop_size}, K={args.seeds}, seed {args.seed}"
                     + ("" if warm is None else ", generation 0 with the scenario's parameters"),
            "summary": f"best fitness {top['mu']:.4f} after {args.generations} generations, {len(hist)} candidates x "
                       f"{args.seeds} seeds" + ("" if math.isfinite(top["mu"]) else " (no finite mu)")}
