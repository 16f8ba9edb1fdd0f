"""``sumo-avoid reproduce formation``: fixed gains against Lévy-tuned gains on seed 003's arena
experiment (SPEC §3), as one batch (process-isolated runs, the SQLite ledger, resumable).

Runs every scenario of ``--scenarios`` (default: the three goals, scenarios/formation/arena_g*.toml)
for every seed of ``--seeds`` twice: with the scenario's gains ("fixed") and with the
``[controllers.formation]`` block of ``--tuned`` (written by ``sumo-avoid tune``), each optionally at
``--obstacles`` N. Writes to ``--out``: ``ledger.sqlite`` (+ csv), ``summary.md`` (per scenario and
variant: goal reached, formation time and S_ef mean +- sd, collisions, obstacle contacts, kappa
shares; the paired Wilcoxon signed-rank test of fixed against tuned on the same seeds) and
``fig_<scenario>.png`` (the first seed's trajectories of both variants, like the seed's Fig. 4-6).
"""
from __future__ import annotations

import io
import json
import pathlib
import sys

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from scipy.stats import wilcoxon

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.spec import read_toml
from sumo_avoid.studies import batch
from sumo_avoid.studies import ledger as ledger_mod
from sumo_avoid.studies.files import write_atomic

ROOT = pathlib.Path(__file__).resolve().parents[2]
DEFAULT = tuple(ROOT / "scenarios" / "formation" / f"arena_g{k}.toml" for k in (1, 2, 3))
COLS = ("goal_reached", "formation_time_s", "s_ef", "i_t", "i_e", "i_d", "collisions", "obstacle_hits",
        "kappa1_share", "kappa2_share", "kappa3_share")


def tuned_overrides(path: pathlib.Path) -> tuple[str, ...]:
    """``--set`` strings of the ``[controllers.formation]`` block of a tuned.toml."""
    block = read_toml(path).get("controllers", {}).get("formation")
    if not block:
        raise ScenarioError(str(path), "controllers.formation", "a [controllers.formation] table (sumo-avoid tune)",
                            show_got=False)
    return tuple(f"controllers.formation.{k}={v!r}" for k, v in sorted(block.items()))


def plan(scenarios, seeds, tuned: tuple[str, ...], extra: tuple[str, ...]) -> dict[str, list]:
    """variant -> RunSpecs (same scenarios and seeds for both)."""
    out = {}
    for name, sets in (("fixed", extra), ("tuned", extra + tuned)):
        out[name] = [batch.plan(s, seed, sets, "formation") for s in scenarios for seed in seeds]
    return out


def paired(df: pd.DataFrame, metric: str) -> tuple[float, float, int]:
    """(mean tuned - fixed, Wilcoxon two-sided p, pairs) over seeds where both runs are done."""
    a = df[df["variant"] == "fixed"].set_index("seed")[metric]
    b = df[df["variant"] == "tuned"].set_index("seed")[metric]
    both = a.index.intersection(b.index)
    a, b = a.loc[both].astype(float), b.loc[both].astype(float)
    ok = a.notna() & b.notna()
    a, b = a[ok], b[ok]
    if len(a) < 2 or np.allclose(a, b):
        return float((b - a).mean()) if len(a) else float("nan"), float("nan"), len(a)
    return float((b - a).mean()), float(wilcoxon(b, a).pvalue), len(a)


def _fmt(x) -> str:
    return "–" if x is None or (isinstance(x, float) and not np.isfinite(x)) else f"{x:.3f}"


def summary(df: pd.DataFrame, command: str, tuned: tuple[str, ...]) -> str:
    lines = ["# Formation control: fixed vs Lévy-tuned gains (seed 003)", "", f"Command: `{command}`", "",
             f"Tuned gains: {', '.join(tuned)}", "",
             ("| scenario | variant | runs | goal reached | formation time s (mean ± sd) | S_ef (mean ± sd) | "
              "I_t | I_e | I_d | collisions | obstacle contacts | kappa 1/2/3 share |"), "|---" * 12 + "|"]
    for (scn, var), g in df.groupby(["scenario", "variant"], sort=True):
        t, s = g["formation_time_s"].astype(float), g["s_ef"].astype(float)
        lines.append(f"| {scn} | {var} | {len(g)} | {int(g['goal_reached'].sum())}/{len(g)} | "
                     f"{_fmt(t.mean())} ± {_fmt(t.std())} | {_fmt(s.mean())} ± {_fmt(s.std())} | "
                     f"{_fmt(g['i_t'].mean())} | {_fmt(g['i_e'].mean())} | {_fmt(g['i_d'].mean())} | "
                     f"{int(g['collisions'].sum())} | {int(g['obstacle_hits'].sum())} | "
                     f"{g['kappa1_share'].mean():.2f}/{g['kappa2_share'].mean():.2f}/{g['kappa3_share'].mean():.2f} |")
    lines += ["", "Paired on the same seeds (Wilcoxon signed-rank, two-sided):", "",
              "| scenario | metric | mean tuned − fixed | p | pairs |", "|---|---|---|---|---|"]
    for scn, g in df.groupby("scenario", sort=True):
        for metric in ("formation_time_s", "s_ef"):
            d, p, n = paired(g, metric)
            lines.append(f"| {scn} | {metric} | {_fmt(d)} | {p:.3g} | {n} |")
    return "\n".join(lines) + "\n"


def figure(df: pd.DataFrame, root: pathlib.Path, scn: str, out_png: pathlib.Path) -> None:
    """The first seed's member trajectories, fixed and tuned side by side, obstacles drawn."""
    fig = Figure(figsize=(11, 5.5))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    seed = int(df[df["scenario"] == scn]["seed"].min())
    for ax, var in zip(axes, ("fixed", "tuned")):
        row = df[(df["scenario"] == scn) & (df["variant"] == var) & (df["seed"] == seed)]
        if row.empty or not isinstance(row.iloc[0]["artifacts"], str):
            continue
        art = root / row.iloc[0]["artifacts"]
        t = pd.read_csv(art / "trajectories.csv")
        for vid, g in t[t["is_ego"]].groupby("id", sort=True):
            ax.plot(g["x"], g["y"], lw=1.0 if vid == "f0" else 0.7, label=vid)
        for pos in (0, len(t) - 1):
            step = t.iloc[pos]["step"]
            s = t[t["step"] == step]
            ax.plot(s["x"], s["y"], "k.", ms=4)
        res = json.loads((art / "metrics.json").read_text())
        for ob in scenario.load(row.iloc[0]["scenario_path"], list(json.loads(row.iloc[0]["overrides"])),
                                seed=seed).spec.obstacles:
            pg = np.asarray(ob.shape)
            ax.fill(pg[:, 0], pg[:, 1], color="0.35")
        ax.set_aspect("equal")
        ax.set_title(f"{scn} · {var} · seed {seed} · T {_fmt(res.get('formation_time_s'))} s · "
                     f"S_ef {_fmt(res.get('s_ef'))}", fontsize=8)
        ax.legend(fontsize=6, loc="lower right")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, bbox_inches="tight")
    write_atomic(out_png, buf.getvalue())


def run(args) -> int:
    seeds = batch.parse_seeds(args.seeds, key="--runs")
    workers = batch.workers_or_cores(args.workers)
    tuned = tuned_overrides(args.tuned)
    extra = ("output.plots=false",) + ((f"random_obstacles.count={args.obstacles}",) if args.obstacles else ())
    scenarios = tuple(args.scenarios) or DEFAULT
    runs = plan(scenarios, seeds, tuned, extra)
    led = args.out / "ledger.sqlite"
    ledger_mod.check(led, "--out")  # a folder that holds (or can hold) the study's ledger
    every = tuple(s for v in runs.values() for s in v)
    cfg = batch.BatchConfig(every, led, workers=workers, scheduler=args.scheduler,
                            retry_failed=bool(getattr(args, "retry_failed", False)))
    c = batch.run_batch(cfg)
    print(f"reproduce formation: {c['done']} done, {c['failed']} failed, {c['skipped']} already recorded -> {led}")
    df = ledger_mod.read(led).set_index("key")
    rows = []
    for var, specs in runs.items():
        part = df.loc[[s.key for s in specs]].reset_index()
        part["variant"] = var
        rows.append(part)
    table = pd.concat(rows, ignore_index=True)
    for col in COLS:
        if col not in table:
            table[col] = np.nan
    command = "sumo-avoid " + " ".join(sys.argv[1:])
    write_atomic(args.out / "summary.md", summary(table, command, tuned))
    write_atomic(args.out / "runs.csv", table[["scenario", "variant", "seed", "status", *COLS]].to_csv(index=False))
    for scn in sorted(table["scenario"].unique()):
        figure(table, led.parent, scn, args.out / f"fig_{scn}.png")
    print((args.out / "summary.md").read_text())
    return 0
