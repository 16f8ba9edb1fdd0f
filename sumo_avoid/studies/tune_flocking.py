"""``sumo-avoid tune flocking``: seed 000's genetic algorithm (SPEC §1.4) over the flocking model's 11
parameters, on the shared tuning engine (:mod:`sumo_avoid.studies.tune`).

The GA is pymoo's real-coded GA over the unit cube [0, 1]^11: random initial population (or, with a
warm start, :class:`WarmStart`, the scenario's own parameters as its first individual), binary
tournament selection, simulated binary crossover (SBX, p 0.9, eta 15), polynomial mutation (eta 20),
duplicates eliminated, and (mu + lambda) survival of the fittest (elitism: the best candidate is never
lost). Each unit coordinate maps onto its parameter's bounds, linearly or, where the bounds span a
decade or more (HI/LO >= 10), log-uniformly; values are rounded to 6 significant digits, the form the
runs and the ledger see. A candidate's fitness is the mean μ (SPEC §1.2; collisions are in μ through
μ_coll) over the K tuning seeds, every evaluation a batch run in the ledger; a failed run counts μ = 0.

Bounds: ``--bound NAME LO HI`` on the command line, else a ``[tune.flocking]`` table of the scenario
(``NAME = [LO, HI]``), else the default: the hull of seed 000's Table 3 working ranges over the three
speeds, widened by 25 % of its width (half on each side, in the scale it is searched in; a linear range
stops at 0, and the four parameters the model needs positive start at 0.05, Table 3's printed "0.0").
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
from pymoo.algorithms.soo.nonconvex.ga import GA, comp_by_cv_and_fitness
from pymoo.core.problem import Problem
from pymoo.core.termination import NoTermination
from pymoo.operators.crossover.sbx import SBX
from pymoo.operators.mutation.pm import PM
from pymoo.operators.sampling.rnd import FloatRandomSampling
from pymoo.operators.selection.tournament import TournamentSelection

from sumo_avoid.core.config import ScenarioError

# seed 000 Table 3: each parameter's working range [LO, HI] at v_flock 4, 6, 8 m/s (candidates with μ >= μ̄)
TABLE3_RANGES = {
    "r0_rep_m": ((17.3, 28.2), (30.8, 51.0), (46.0, 63.5)),
    "p_rep_ps": ((0.08, 0.37), (0.03, 0.16), (0.04, 0.09)),
    "r0_frict_m": ((51.3, 87.8), (58.5, 100.0), (52.2, 114.0)),
    "c_frict": ((0.02, 0.27), (0.03, 0.22), (0.04, 0.17)),
    "v_frict_mps": ((0.07, 1.88), (0.30, 2.70), (0.81, 3.10)),
    "p_frict_ps": ((0.0, 10.0), (0.38, 9.67), (1.66, 9.97)),
    "a_frict_mps2": ((0.0, 10.0), (5.04, 10.0), (0.0, 2.89)),
    "r0_shill_m": ((0.0, 15.1), (0.0, 9.3), (0.0, 3.5)),
    "v_shill_mps": ((9.4, 15.0), (17.5, 20.0), (17.8, 34.1)),
    "p_shill_ps": ((0.26, 10.0), (0.48, 9.96), (4.32, 10.0)),
    "a_shill_mps2": ((1.24, 9.99), (2.53, 5.12), (2.39, 9.99)),
}
PARAMS = tuple(TABLE3_RANGES)  # the 11 tuned keys of [controllers.flocking]
POSITIVE = ("p_frict_ps", "a_frict_mps2", "p_shill_ps", "a_shill_mps2")  # FlockingParams refuses <= 0
POSITIVE_FLOOR = 0.05
WIDEN = 0.25
LOG_RATIO = 10.0
FAILED_MU = 0.0
START_FROM = ("random", "scenario")  # --start-from: generation 0 all random, or the scenario's parameters in it


@dataclass(frozen=True)
class Bound:
    """One parameter's search range; ``log``: searched log-uniformly."""

    name: str
    lo: float
    hi: float
    log: bool


def spans_decades(lo: float, hi: float) -> bool:
    return lo > 0 and hi / lo >= LOG_RATIO


def widened(lo: float, hi: float, floor: float) -> Bound:
    """``[lo, hi]`` widened by WIDEN of its width, half each side, in its search scale, not below ``floor``."""
    lo = max(lo, floor)
    if spans_decades(lo, hi):
        a, b = math.log10(lo), math.log10(hi)
        pad = WIDEN / 2 * (b - a)
        return Bound("", max(10 ** (a - pad), floor), 10 ** (b + pad), True)
    pad = WIDEN / 2 * (hi - lo)
    return Bound("", max(lo - pad, floor), hi + pad, False)


def default_bounds() -> tuple[Bound, ...]:
    """The hull of Table 3's ranges over the three speeds, widened (module doc)."""
    out = []
    for name, ranges in TABLE3_RANGES.items():
        b = widened(min(r[0] for r in ranges), max(r[1] for r in ranges), POSITIVE_FLOOR if name in POSITIVE else 0.0)
        out.append(Bound(name, float(f"{b.lo:.6g}"), float(f"{b.hi:.6g}"), b.log))
    return tuple(out)


def bounds(cli: list, table: dict, where: str) -> tuple[Bound, ...]:
    """The search space: ``--bound`` (``[[name, lo, hi], ...]``) over the scenario's ``[tune.flocking]``
    table (``where`` names it in errors) over the defaults. Raises ScenarioError on a bad bound."""
    given = {}
    for key, val in table.items():
        if not (isinstance(val, list) and len(val) == 2 and all(isinstance(v, (int, float)) and
                                                                 not isinstance(v, bool) for v in val)):
            raise ScenarioError(where, f"tune.flocking.{key}", "a pair of numbers [LO, HI]", val)
        given[key] = (f"tune.flocking.{key}", where, float(val[0]), float(val[1]))
    for name, lo, hi in cli:
        given[name] = ("--bound", "<command line>", float(lo), float(hi))
    out = []
    for b in default_bounds():
        if b.name not in given:
            out.append(b)
            continue
        key, file, lo, hi = given.pop(b.name)
        floor = POSITIVE_FLOOR if b.name in POSITIVE else 0.0
        if not (math.isfinite(lo) and math.isfinite(hi) and floor <= lo < hi):
            raise ScenarioError(file, key, f"{b.name}: finite {floor:g} <= LO < HI", [lo, hi])
        out.append(Bound(b.name, lo, hi, spans_decades(lo, hi)))
    if given:
        key, file, *_ = given[next(iter(given))]
        raise ScenarioError(file, key, f"one of the tuned parameters {list(PARAMS)}", next(iter(given)))
    return tuple(out)


def values(unit, space: tuple[Bound, ...]) -> np.ndarray:
    """Unit-cube points (n, D) -> parameter values (n, D), 6 significant digits."""
    u = np.atleast_2d(np.asarray(unit, float))
    out = np.empty_like(u)
    for k, b in enumerate(space):
        if b.log:
            a, c = math.log10(b.lo), math.log10(b.hi)
            v = 10 ** (a + u[:, k] * (c - a))
        else:
            v = b.lo + u[:, k] * (b.hi - b.lo)
        out[:, k] = [float(f"{x:.6g}") for x in v]
    return out


@dataclass(frozen=True)
class WarmStart:
    """A point put into generation 0 as its first individual: ``unit`` its coordinates in [0, 1]^D (in the
    search space's order); ``clipped`` (name, value, LO, HI) of each value that lay outside its bounds."""

    unit: tuple[float, ...]
    clipped: tuple[tuple[str, float, float, float], ...] = ()

    def note(self) -> str:
        """The clipped values in one line ('' if none)."""
        return "; ".join(f"{n} = {v:g} lies outside its bounds [{lo:g}, {hi:g}], clipped to {min(max(v, lo), hi):g}"
                         for n, v, lo, hi in self.clipped)


def warm_start(params, space: tuple[Bound, ...]) -> WarmStart:
    """``params`` (e.g. the scenario's FlockingParams: an attribute per tuned key) in the unit cube: the
    inverse of :func:`values`, linear or log as the bound is searched; a value outside [LO, HI] is clipped
    to the nearer bound first (so :func:`values` gives back the bound)."""
    unit, clipped = [], []
    for b in space:
        v = float(getattr(params, b.name))
        c = min(max(v, b.lo), b.hi)
        if c != v:
            clipped.append((b.name, v, b.lo, b.hi))
        if b.log:
            u = (math.log10(c) - math.log10(b.lo)) / (math.log10(b.hi) - math.log10(b.lo))
        else:
            u = (c - b.lo) / (b.hi - b.lo)
        unit.append(min(max(u, 0.0), 1.0))
    return WarmStart(tuple(unit), tuple(clipped))


def overrides(row, space: tuple[Bound, ...], fixed: tuple[str, ...]) -> tuple[str, ...]:
    """A candidate's ``--set`` overrides: ``fixed`` (the preset cleared, v_flock and v_max kept) and the values."""
    return fixed + tuple(f"controllers.flocking.{b.name}={float(v)!r}" for b, v in zip(space, row))


def fixed_overrides(params) -> tuple[str, ...]:
    """The scenario's preset cleared (a preset would replace a candidate's value that equals the key's
    default), its speeds kept."""
    return ('controllers.flocking.preset=""', f"controllers.flocking.v_flock_mps={params.v_flock_mps!r}",
            f"controllers.flocking.v_max_mps={params.v_max_mps!r}")


def fitness(rows: pd.DataFrame) -> float:
    """Mean μ over a candidate's runs (ledger rows); a failed run counts FAILED_MU."""
    vals = [float(r.mu) if r.status == "done" and r.mu is not None and not pd.isna(r.mu) else FAILED_MU
            for r in rows.itertuples()]
    return float(np.mean(vals))


def make_ga(dim: int, pop_size: int, seed: int) -> GA:
    """pymoo's GA set up for ask/tell over [0, 1]^dim, its random stream from ``seed``."""
    algo = GA(pop_size=pop_size, sampling=FloatRandomSampling(),
              selection=TournamentSelection(func_comp=comp_by_cv_and_fitness),
              crossover=SBX(prob=0.9, eta=15), mutation=PM(eta=20), eliminate_duplicates=True)
    algo.setup(Problem(n_var=dim, n_obj=1, xl=0.0, xu=1.0), termination=NoTermination(), seed=seed, verbose=False)
    return algo


def search(ev, space: tuple[Bound, ...], fixed: tuple[str, ...], generations: int, pop_size: int, seed: int,
           bar=None, start: WarmStart | None = None) -> tuple[list[dict], list[dict]]:
    """Generation 0 (the initial population) and ``generations`` more, each its offspring evaluated as one
    batch. ``start``: generation 0's first individual is that point instead of its random draw (the
    random stream and the other individuals are those of a search without it). Returns the history
    (every candidate: generation, values, mu) and the generation rows (the population after survival:
    best, mean, worst μ, the best candidate's values)."""
    algo = make_ga(len(space), pop_size, seed)
    hist: list[dict] = []
    gens: list[dict] = []
    names = [b.name for b in space]
    for gen in range(generations + 1):
        pop = algo.ask()
        if gen == 0 and start is not None:
            pop[0].set("X", np.asarray(start.unit, float))
        vals = values(pop.get("X"), space)
        mus = ev([overrides(v, space, fixed) for v in vals])
        pop.set("F", -np.asarray(mus, float)[:, None])
        algo.tell(infills=pop)
        hist += [{"generation": gen, **dict(zip(names, map(float, v))), "mu": m} for v, m in zip(vals, mus)]
        f = -algo.pop.get("F")[:, 0]
        best = values(algo.pop[int(np.argmax(f))].get("X"), space)[0]
        gens.append({"generation": gen, "evaluations": len(hist), "best_mu": float(f.max()),
                     "mean_mu": float(f.mean()), "worst_mu": float(f.min()), **dict(zip(names, map(float, best)))})
        if bar is not None:
            bar.set_postfix(best=f"{f.max():.4f}", refresh=False)
            bar.update(1)
    return hist, gens


def best_of(hist: pd.DataFrame) -> pd.Series:
    """The candidate with the highest fitness (the first such, in evaluation order)."""
    return hist.loc[hist["mu"].idxmax()]
