"""The seed's statistics of a tuning (seed 000 Table 3, SPEC §1.4): the best candidate evaluated afresh
on R seeds the tuner never saw, beside the scenario's own parameters on the same seeds.

* μ_max: the best of the R fresh evaluations; μ̄ ± sd: their mean and sample sd (ddof 1);
* N(μ ≥ μ̄): how many of the tuner's candidates reached a fitness (mean μ over its K seeds) of at least μ̄,
  and each parameter's range among them (Table 3's brackets);
* the scenario's parameters (e.g. the paper's Table 3 preset) on the same R seeds, and a paired
  two-sided Wilcoxon signed-rank test of tuned against them (scipy; zero differences dropped, "wilcox").
"""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import pandas as pd
from scipy import stats as sps

from sumo_avoid.studies.files import write_atomic

METRICS = ("mu", "phi_coll", "phi_wall", "collisions")


def per_seed(rows: pd.DataFrame, prefix: str) -> pd.DataFrame:
    """A candidate's fresh runs (ledger rows) as ``seed, PREFIX_mu, ...`` (a failed run: μ 0, others NaN)."""
    out = pd.DataFrame({"seed": rows["seed"].astype(int).to_numpy()})
    done = (rows["status"] == "done").to_numpy()
    for m in METRICS:
        v = pd.to_numeric(rows[m], errors="coerce").to_numpy(float)
        out[f"{prefix}_{m}"] = np.where(done, v, 0.0 if m == "mu" else np.nan)
    return out


def _summary(v: np.ndarray) -> dict:
    return {"mu_max": float(v.max()), "mu_mean": float(v.mean()),
            "mu_sd": float(v.std(ddof=1)) if len(v) > 1 else None}


def wilcoxon(a: np.ndarray, b: np.ndarray) -> dict:
    """Paired two-sided Wilcoxon signed-rank test of a against b; median difference a - b."""
    d = np.asarray(a, float) - np.asarray(b, float)
    out = {"pairs": int(len(d)), "median_diff": float(np.median(d)) if len(d) else None, "statistic": None, "p": None}
    if np.count_nonzero(d) == 0:
        out["p"] = 1.0 if len(d) else None
        return out
    r = sps.wilcoxon(a, b, zero_method="wilcox", alternative="two-sided")
    out.update(statistic=float(r.statistic), p=float(r.pvalue))
    return out


def statistics(hist: pd.DataFrame, names, best: dict, evals: pd.DataFrame) -> dict:
    """The seed's statistics from the tuning history, the best candidate and its fresh evaluations
    (``evals``: columns ``tuned_*`` and ``baseline_*`` per seed)."""
    s = _summary(evals["tuned_mu"].to_numpy(float))
    above = hist[hist["mu"] >= s["mu_mean"]]
    s.update(R=int(len(evals)), eval_seeds=[int(x) for x in evals["seed"]], n_candidates=int(len(hist)),
             n_above_mean=int(len(above)),
             ranges={n: ([float(above[n].min()), float(above[n].max())] if len(above) else None) for n in names},
             best=best, baseline=_summary(evals["baseline_mu"].to_numpy(float)),
             wilcoxon_mu=wilcoxon(evals["tuned_mu"], evals["baseline_mu"]))
    for who in ("tuned", "baseline"):
        for m in ("phi_coll", "phi_wall", "collisions"):
            v = evals[f"{who}_{m}"].to_numpy(float)
            s[f"{who}_{m}_mean"] = float(np.nanmean(v)) if np.isfinite(v).any() else None
    return s


def _f(x, fmt="{:.3f}") -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else fmt.format(x)


def write(s: dict, out: pathlib.Path, command: str, baseline_name: str) -> None:
    """``statistics.json`` and ``statistics.md``."""
    write_atomic(out / "statistics.json", json.dumps({"command": command, **s}, indent=1, sort_keys=True) + "\n")
    w = s["wilcoxon_mu"]
    lines = ["# Tuning statistics (seed 000 Table 3's form)", "", f"Command: `{command}`", "",
             f"Best candidate's tuning fitness (mean μ over the K tuning seeds): {_f(s['best']['fitness'], '{:.4f}')}",
             "", f"Fresh evaluations: R = {s['R']} seeds the tuner never saw ({s['eval_seeds'][0]}.."
             f"{s['eval_seeds'][-1]}), the same seeds for {baseline_name}.", "",
             f"| | tuned | {baseline_name} |", "|---|---|---|",
             f"| μ_max | {_f(s['mu_max'])} | {_f(s['baseline']['mu_max'])} |",
             f"| μ̄ ± sd | {_f(s['mu_mean'])} ± {_f(s['mu_sd'])} | {_f(s['baseline']['mu_mean'])} ± "
             f"{_f(s['baseline']['mu_sd'])} |",
             f"| φ_coll (mean) | {_f(s['tuned_phi_coll_mean'], '{:.3g}')} | "
             f"{_f(s['baseline_phi_coll_mean'], '{:.3g}')} |",
             f"| φ_wall (mean, m) | {_f(s['tuned_phi_wall_mean'], '{:.3g}')} | "
             f"{_f(s['baseline_phi_wall_mean'], '{:.3g}')} |",
             f"| footprint collisions per run | {_f(s['tuned_collisions_mean'], '{:.2f}')} | "
             f"{_f(s['baseline_collisions_mean'], '{:.2f}')} |", "",
             f"Paired Wilcoxon signed-rank (two-sided), μ tuned − {baseline_name}, {w['pairs']} pairs: median "
             f"difference {_f(w['median_diff'], '{:+.4f}')}, W = {_f(w['statistic'], '{:g}')}, p = "
             f"{_f(w['p'], '{:.3g}')}.", "",
             f"N(μ ≥ μ̄) = {s['n_above_mean']} of {s['n_candidates']} candidates (fitness over the tuning "
             "seeds).", "",
             "| parameter | best | range among candidates with μ ≥ μ̄ |", "|---|---|---|"]
    for n, r in s["ranges"].items():
        lines.append(f"| {n} | {s['best'][n]:.6g} | " + (f"[{r[0]:.6g}, {r[1]:.6g}]" if r else "–") + " |")
    write_atomic(out / "statistics.md", "\n".join(lines) + "\n")
