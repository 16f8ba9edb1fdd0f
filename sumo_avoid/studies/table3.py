"""``sumo-avoid reproduce table3``: seed 000's Table 3 (SPEC §1.4) inside SUMO: the flocking tuner's GA
(:mod:`sumo_avoid.studies.tune`, ``tune flocking``) on the Table 4 arena at v_flock 4, 6 and 8 m/s,
its statistics beside the paper's.

Per speed, into ``OUT/v{V}/``, exactly ``sumo-avoid tune flocking scenarios/arena_v{V}.toml`` with the
budget flags (every evaluation a batch run in that folder's ledger: a killed study resumes by re-running
the command). The best candidate and the paper's Table 3 parameters (the scenario's preset) are then
evaluated on the same R fresh seeds. ``--start-from scenario`` warm-starts each speed's GA from the
paper's parameters (generation 0's first individual; ``tune flocking --start-from``). Writes
``table3.csv`` (``v_flock, quantity, ours, ours_lo, ours_hi, paper, paper_lo, paper_hi``), ``table3.md``
(side by side, with the command, the budget and how far the paper's μ̄ and μ_max are missed, if they
are) and ``convergence.png`` (one panel per speed).
"""
from __future__ import annotations

import argparse
import io
import json
import pathlib
import sys

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from sumo_avoid.control.flocking.terms import PRESETS
from sumo_avoid.studies import tune
from sumo_avoid.studies.files import make_dirs, write_atomic
from sumo_avoid.studies.table4 import ROOT, SPEEDS
from sumo_avoid.studies.tune_flocking import PARAMS, TABLE3_RANGES

# seed 000 Table 3: μ_max, μ̄ ± sd over its 100 evaluations, N(μ >= μ̄)
PAPER = {4: {"mu_max": 0.918, "mu_mean": 0.812, "mu_sd": 0.101, "n_above_mean": 1855},
         6: {"mu_max": 0.873, "mu_mean": 0.776, "mu_sd": 0.086, "n_above_mean": 2118},
         8: {"mu_max": 0.798, "mu_mean": 0.728, "mu_sd": 0.075, "n_above_mean": 2030}}


def add_arguments(r) -> None:
    g = r.add_argument_group("table3 (the GA at each speed; --seeds R fresh seeds from --first-seed, --agents, "
                             "--duration, --workers, --scheduler as above)")
    g.add_argument("--generations", type=int, default=10, help="table3: GA generations per speed (default 10)")
    g.add_argument("--pop-size", type=int, default=24, help="table3: GA population (default 24)")
    g.add_argument("--tune-seeds", type=int, default=3, help="table3: K tuning seeds per candidate (default 3)")
    g.add_argument("--tune-first-seed", type=int, default=101, help="table3: the K seeds start here (default 101)")
    g.add_argument("--search-seed", type=int, default=1, help="table3: the GA's random seed (default 1)")
    g.add_argument("--speeds", type=int, nargs="+", default=list(SPEEDS), choices=SPEEDS,
                   help="table3: v_flock values (default 4 6 8)")
    g.add_argument("--start-from", default="random", metavar="random|scenario",
                   help="table3: generation 0 all random (default), or 'scenario': with the paper's Table 3 "
                        "parameters (the arena's preset) as one individual: can the GA improve on them in SUMO?")


def tune_args(args, v: int, out: pathlib.Path) -> argparse.Namespace:
    """The ``tune flocking`` command line of speed ``v``."""
    sets = [f"arena.n_agents={args.agents}", f"sim.duration_s={float(args.duration)}", *args.overrides]
    return argparse.Namespace(
        controller="flocking", scenario=ROOT / "scenarios" / f"arena_v{v}.toml", generations=args.generations,
        seeds=args.tune_seeds, first_seed=args.tune_first_seed, seed=args.search_seed, overrides=sets,
        workers=args.workers, scheduler=args.scheduler, ledger=None, out=out / f"v{v}", quiet=False,
        pop_size=args.pop_size, bound=[], evals=args.seeds, eval_first_seed=args.first_seed,
        start_from=args.start_from)


def rows_of(v: int, s: dict) -> list[dict]:
    """table3.csv's rows of one speed from its statistics.json."""
    p = PAPER[v]
    rows = [{"v_flock": v, "quantity": q, "ours": s[q], "paper": p[q]} for q in ("mu_max", "mu_mean", "mu_sd",
                                                                                  "n_above_mean")]
    rows += [{"v_flock": v, "quantity": f"paper_params_{q}", "ours": s["baseline"][q]} for q in ("mu_max", "mu_mean",
                                                                                                "mu_sd")]
    rows += [{"v_flock": v, "quantity": q, "ours": s[q]}
             for q in ("tuned_phi_coll_mean", "baseline_phi_coll_mean", "tuned_collisions_mean",
                       "baseline_collisions_mean")]
    rows.append({"v_flock": v, "quantity": "wilcoxon_p_mu", "ours": s["wilcoxon_mu"]["p"]})
    k = SPEEDS.index(v)
    for n in PARAMS:
        rng = s["ranges"][n] or [None, None]
        lo, hi = TABLE3_RANGES[n][k]
        rows.append({"v_flock": v, "quantity": n, "ours": s["best"][n], "ours_lo": rng[0], "ours_hi": rng[1],
                     "paper": PRESETS[f"paper_v{v}"][n], "paper_lo": lo, "paper_hi": hi})
    return rows


def verdict(v: int, s: dict) -> str:
    """Whether the tuned μ̄ and μ_max reach the paper's, and by how much they miss."""
    out = []
    for q, name in (("mu_mean", "μ̄"), ("mu_max", "μ_max")):
        d = s[q] - PAPER[v][q]
        out.append(f"{name} {s[q]:.3f} {'reaches' if d >= 0 else 'misses'} the paper's {PAPER[v][q]:.3f} "
                   f"({d:+.3f})")
    d = s["mu_mean"] - s["baseline"]["mu_mean"]
    w = s["wilcoxon_mu"]
    p = "–" if w["p"] is None else f"{w['p']:.3g}"
    return (f"v_flock {v}: " + "; ".join(out) + f"; against the paper's parameters on the same {s['R']} seeds "
            f"{d:+.3f} (their μ̄ {s['baseline']['mu_mean']:.3f}; Wilcoxon p = {p}); φ_coll tuned "
            f"{s['tuned_phi_coll_mean']:.3g}, paper's parameters {s['baseline_phi_coll_mean']:.3g}")


def _f(x, fmt="{:.3g}") -> str:
    return "–" if x is None or (isinstance(x, float) and np.isnan(x)) else fmt.format(x)


def write_md(stats: dict, out: pathlib.Path, command: str, settings: str) -> None:
    lines = ["# Table 3 (seed 000) reproduced in SUMO: the GA's tuning", "", f"Command: `{command}`", "", settings, "",
             *[f"* {verdict(v, s)}" for v, s in stats.items()], "",
             "| quantity | " + " | ".join(f"v{v} ours | v{v} paper" for v in stats) + " |",
             "|---" * (1 + 2 * len(stats)) + "|"]
    for q in ("mu_max", "mu_mean", "n_above_mean"):
        cells = []
        for v, s in stats.items():
            fmt = "{:d}" if q == "n_above_mean" else "{:.3f}"
            ours = f"{s[q]:.3f} ± {_f(s['mu_sd'], '{:.3f}')}" if q == "mu_mean" else _f(s[q], fmt)
            paper = f"{PAPER[v][q]:.3f} ± {PAPER[v]['mu_sd']:.3f}" if q == "mu_mean" else fmt.format(PAPER[v][q])
            cells.append(f"{ours} | {paper}")
        lines.append(f"| {q} | " + " | ".join(cells) + " |")
    for n in PARAMS:
        cells = []
        for v, s in stats.items():
            r, (lo, hi) = s["ranges"][n], TABLE3_RANGES[n][SPEEDS.index(v)]
            ours = f"{s['best'][n]:.3g} [{_f(r[0])}, {_f(r[1])}]" if r else f"{s['best'][n]:.3g}"
            cells.append(f"{ours} | {PRESETS[f'paper_v{v}'][n]:.3g} [{lo:g}, {hi:g}]")
        lines.append(f"| {n} | " + " | ".join(cells) + " |")
    lines += ["", "Ours: the best candidate's values, [the range among candidates whose fitness reached our μ̄]; "
              "μ_max and μ̄ ± sd over the R fresh evaluations of the best candidate; N(μ ≥ μ̄) among all our "
              "candidates. Per speed: `v{V}/statistics.md`, `generations.csv`, `history.csv`, `evaluations.csv`."]
    write_atomic(out / "table3.md", "\n".join(lines) + "\n")


def plot(gens: dict, stats: dict, out_png: pathlib.Path) -> None:
    """Per speed: the population's best and mean by generation, the paper's μ_max and μ̄, and (after the
    last generation) μ̄ ± sd of the best candidate and of the paper's parameters on the fresh seeds."""
    fig = Figure(figsize=(4 * len(gens), 3.6))
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(1, len(gens), sharey=True))
    for ax, (v, g) in zip(axes, gens.items()):
        s, end = stats[v], float(g["generation"].max())
        ax.plot(g["generation"], g["best_mu"], "b-o", ms=4, label="population best (K tuning seeds)")
        ax.plot(g["generation"], g["mean_mu"], "g--", label="population mean")
        ax.axhline(PAPER[v]["mu_max"], color="k", ls=":", lw=1, label="paper μ_max")
        ax.axhline(PAPER[v]["mu_mean"], color="0.5", ls="-.", lw=1, label="paper μ̄")
        ax.errorbar([end + 0.3], [s["mu_mean"]], [s["mu_sd"] or 0.0], fmt="bs", ms=5, capsize=3,
                    label=f"best, R = {s['R']} fresh seeds")
        ax.errorbar([end + 0.5], [s["baseline"]["mu_mean"]], [s["baseline"]["mu_sd"] or 0.0], fmt="k^", ms=5,
                    capsize=3, label="paper's parameters, same seeds")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_title(f"v_flock = {v} m/s", fontsize=9)
        ax.set_xlabel("generation")
    axes[0].set_ylabel("μ")
    axes[0].legend(fontsize=6, loc="lower left")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    write_atomic(out_png, buf.getvalue())


def run(args) -> int:
    out = args.out or ROOT / "reports" / "table3"
    per_speed = {v: tune_args(args, v, out) for v in args.speeds}
    prepared = {v: tune.prepare(ns) for v, ns in per_speed.items()}  # every bad input before anything runs
    make_dirs(out, "--out")
    stats, gens = {}, {}
    try:
        for v, ns in per_speed.items():
            print(f"reproduce table3: v_flock {v} -> {ns.out}", flush=True)
            res = tune.execute(ns, *prepared[v])
            gens[v] = res["generations"]
            stats[v] = json.loads((ns.out / "statistics.json").read_text())
    except KeyboardInterrupt:
        print("reproduce table3: interrupted; re-run the same command to resume", file=sys.stderr)
        return 130
    write_atomic(out / "table3.csv", pd.DataFrame(
        [r for v, s in stats.items() for r in rows_of(v, s)],
        columns=["v_flock", "quantity", "ours", "ours_lo", "ours_hi", "paper", "paper_lo", "paper_hi"]).to_csv(index=False))
    command = (f"sumo-avoid reproduce table3 --speeds {' '.join(map(str, args.speeds))} --agents {args.agents} "
               f"--duration {args.duration:g} --generations {args.generations} --pop-size {args.pop_size} "
               f"--tune-seeds {args.tune_seeds} --tune-first-seed {args.tune_first_seed} --search-seed "
               f"{args.search_seed} --seeds {args.seeds} --first-seed {args.first_seed}"
               + "".join(f" --set {s}" for s in args.overrides)
               + ("" if args.start_from == "random" else f" --start-from {args.start_from}") + f" --out {out}")
    settings = (f"Budget per speed: GA population {args.pop_size}, generations {args.generations} (+ the initial one), "
                f"K = {args.tune_seeds} tuning seeds from {args.tune_first_seed}, search seed {args.search_seed}"
                + ("" if args.start_from == "random" else ", generation 0 warm-started with the paper's parameters")
                + f"; R = {args.seeds} fresh seeds from {args.first_seed}; N = {args.agents} vehicles, "
                f"{args.duration:g} s per run" + (f", overrides {list(args.overrides)}" if args.overrides else "")
                + ". The paper: 100 vehicles, 600 s, its GA's budget not stated (N(μ ≥ μ̄) ≈ 2000 candidates).")
    write_md(stats, out, command, settings)
    plot(gens, stats, out / "convergence.png")
    for v, s in stats.items():
        print(verdict(v, s))
    return 0
