"""The formation's road case over many seeds (issue: formation control, road case).

    python -m sumo_avoid.studies.formation_road --seeds 1-10 --workers 2 --out reports/formation/road \
        [--scenario scenarios/formation/road_closure.toml] [--set KEY=VALUE ...]

One batch (process-isolated runs, the SQLite ledger in ``--out``, resumable) of the scenario over the
seeds; then ``summary.md`` and ``runs.csv`` in ``--out``: per seed goal, time to goal, collisions (ours,
SUMO's), ``phi_wall``, smallest gap, the kappa shares and where the leader was (x, m) when kappa first
became 2 and 3 and came back to 1 after that, beside where the geometry puts them (the closures,
``CLOSURES``).
"""
from __future__ import annotations

import argparse
import json
import pathlib
import sys

import numpy as np
import pandas as pd

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.studies import batch
from sumo_avoid.studies import ledger as ledger_mod

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "formation" / "road_closure.toml"
#: The road case's closures: (x where the stopped cars start, m; free lanes left; the kappa that implies).
CLOSURES = ((600.0, 2, 2), (1000.0, 1, 3))
COLS = ("goal_reached", "time_to_goal_s", "collisions", "sumo_collisions", "phi_wall", "min_gap_m", "s_ef",
        "kappa1_share", "kappa2_share", "kappa3_share")


def mode_x(run_dir: pathlib.Path) -> tuple[float, float, float]:
    """x of the leader (the first member) when the mode first became 2, first became 3, and first came
    back to 1 after that (NaN where it never did)."""
    m = json.loads((run_dir / "metrics.json").read_text())
    log = m.get("formation_mode_log") or []
    t2 = next((t for t, k in log if k == 2), None)
    t3 = next((t for t, k in log if k == 3), None)
    t1 = None if t3 is None else next((t for t, k in log if k == 1 and t > t3), None)
    tr = pd.read_csv(run_dir / "trajectories.csv", usecols=["time_s", "id", "is_ego", "x"])
    lead = tr[tr["is_ego"].astype(bool)]
    lead = lead[lead["id"] == sorted(lead["id"].unique())[0]]
    return tuple(float("nan") if t is None else float(np.interp(t, lead["time_s"], lead["x"])) for t in (t2, t3, t1))


def summary(df: pd.DataFrame, command: str) -> str:
    n = len(df)
    ok = df["status"] == "done"
    lines = [f"`{command}`", "",
             f"goal reached {int(df['goal_reached'].fillna(0).sum())}/{n}, collisions {int(df['collisions'].fillna(0).sum())} "
             f"(SUMO's {int(df['sumo_collisions'].fillna(0).sum())}), max phi_wall {df['phi_wall'].max():.3f} m, "
             f"smallest gap {df['min_gap_m'].min():.2f} m, failed runs {int((~ok).sum())}", "",
             "closures: " + ", ".join(f"x {x:.0f} m leaves {f} lane(s) free -> kappa {k}" for x, f, k in CLOSURES), "",
             "| seed | goal | time s | coll. ours/SUMO | phi_wall m | min gap m | S_ef | kappa 1/2/3 share | x at kappa 2 | x at kappa 3 | x back at 1 |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in df.sort_values("seed").iterrows():
        lines.append(f"| {r['seed']} | {int(r['goal_reached'] or 0)} | {r['time_to_goal_s']:.1f} | {int(r['collisions'] or 0)}/"
                     f"{int(r['sumo_collisions'] or 0)} | {r['phi_wall']:.3f} | {r['min_gap_m']:.2f} | {r['s_ef']:.3f} | "
                     f"{r['kappa1_share']:.2f}/{r['kappa2_share']:.2f}/{r['kappa3_share']:.2f} | {r['x_kappa2']:.0f} | "
                     f"{r['x_kappa3']:.0f} | {r['x_kappa1']:.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", type=pathlib.Path, default=SCENARIO)
    ap.add_argument("--seeds", default="1-10")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--set", dest="overrides", action="append", default=[])
    ap.add_argument("--out", type=pathlib.Path, default=ROOT / "reports" / "formation" / "road")
    a = ap.parse_args(argv)
    led = a.out / "ledger.sqlite"
    try:
        seeds = batch.parse_seeds(a.seeds, key="--seeds")
        workers = batch.workers_or_cores(a.workers)
        ledger_mod.check(led, "--out")
        specs = tuple(batch.plan(a.scenario, s, ("output.plots=false", *a.overrides), None) for s in seeds)
    except ScenarioError as e:  # bad input: one line, exit 2, nothing written
        print(f"error: {e}", file=sys.stderr)
        return 2
    c = batch.run_batch(batch.BatchConfig(specs, led, workers=workers))
    print(f"formation road: {c['done']} done, {c['failed']} failed, {c['skipped']} already recorded -> {led}")
    df = ledger_mod.read(led).set_index("key").loc[[s.key for s in specs]].reset_index()
    for col in COLS:
        if col not in df:
            df[col] = np.nan
    xs = [mode_x(led.parent / p) if st == "done" and isinstance(p, str) and p else (np.nan,) * 3
          for p, st in zip(df["artifacts"], df["status"])]  # a failed run's cause is in runs.csv
    df["x_kappa2"], df["x_kappa3"], df["x_kappa1"] = (list(c) for c in zip(*xs))
    (a.out / "summary.md").write_text(summary(df, "python -m sumo_avoid.studies.formation_road " + " ".join(sys.argv[1:])))
    df[["seed", "status", "error", *COLS, "x_kappa2", "x_kappa3", "x_kappa1"]].to_csv(a.out / "runs.csv", index=False)
    print((a.out / "summary.md").read_text())
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
