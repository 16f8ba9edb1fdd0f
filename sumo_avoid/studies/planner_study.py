"""The planner study's own table: each run's driven path against the shortest collision-free path
on the full map, and the plan logs' share of plans usable within 20 generations (seed 004's claim).

    python -m sumo_avoid.studies.planner_study reports/planner --scenario scenarios/planner/field.toml \\
        [--inflate 0.9] [--md reports/planner/reference.md]

Reads every finished run under ``DIR/runs/`` (as ``sumo-avoid batch`` writes them) whose
``plans.csv`` exists (a path planner's runs), the ego's first recorded position and its goal; the
reference is :func:`sumo_avoid.planning.reference.shortest_path` around the scenario's obstacles
grown by ``--inflate`` (half the car's width). Prints a markdown table and the totals.
"""
from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np
import pandas as pd

from sumo_avoid.planning.reference import shortest_path
from sumo_avoid.scenario import spec


def study_table(root, obstacles, inflate_m: float) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(one row per planner run, every plan of those runs)."""
    rows, plans = [], []
    for d in sorted(pathlib.Path(root).glob("runs/*")):
        if not (d / "plans.csv").exists() or not (d / "metrics.json").exists():
            continue
        m = json.loads((d / "metrics.json").read_text())
        traj = pd.read_csv(d / "trajectories.csv")
        log = pd.read_csv(d / "plans.csv")
        for ego, drv in traj[traj["is_ego"]].sort_values("step").groupby("id"):
            start = drv[["x", "y"]].to_numpy()[0]
            goal = np.array([float(v) for v in log[log["ego"] == ego]["path"].iloc[0].split(";")[-1].split()])
            ref, _ = shortest_path(start, goal, obstacles, inflate_m)
            mine = log[log["ego"] == ego]
            usable = mine["generation_usable"]
            rows.append({"seed": m["seed"], "controller": m["controller"], "ego": ego, "goal_reached": m["goal_reached"],
                         "collisions": m["collisions"], "phi_wall": m["phi_wall"],
                         "path_m": m["per_ego"][ego]["path_length_m"] if "per_ego" in m else m["path_length_m"],
                         "reference_m": ref, "plans": len(mine),
                         "usable_within_20": float(usable.between(0, 20).mean())})
            plans.append(mine.assign(seed=m["seed"]))
    df = pd.DataFrame(rows)
    if len(df):
        df = df.sort_values(["controller", "seed", "ego"]).reset_index(drop=True)
        df["ratio"] = df["path_m"] / df["reference_m"]
    return df, (pd.concat(plans) if plans else pd.DataFrame())


def summary(df: pd.DataFrame, plans: pd.DataFrame) -> str:
    if not len(df):
        return "no planner runs\n"
    done = df[df["goal_reached"].astype(bool)]
    u = plans["generation_usable"]
    lines = ["| seed | goal | collisions | phi_wall (m) | driven (m) | reference (m) | ratio | plans | usable by gen. 20 |",
             "|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r.seed} | {'yes' if r.goal_reached else 'no'} | {r.collisions} | {r.phi_wall:.3f} | {r.path_m:.1f} | "
              f"{r.reference_m:.1f} | {r.ratio:.3f} | {r.plans} | {r.usable_within_20:.0%} |" for r in df.itertuples()]
    lines += ["", (f"goal reached {len(done)}/{len(df)}; collisions {int(df['collisions'].sum())}; runs with phi_wall > 0: "
                  f"{int((df['phi_wall'] > 0).sum())}"),
              (f"mean driven / reference over the runs that reached the goal: {done['ratio'].mean():.3f} "
              f"({done['path_m'].mean():.1f} m / {done['reference_m'].mean():.1f} m)"),
              (f"plans {len(plans)}: usable (collision-free) by generation 20: {int(u.between(0, 20).sum())} "
              f"({u.between(0, 20).mean():.1%}); never: {int((u < 0).sum())}")]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir")
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--inflate", type=float, default=0.9)
    ap.add_argument("--md")
    args = ap.parse_args(argv)
    obstacles = [o.polygon for o in spec.load(args.scenario).spec.obstacles]
    text = summary(*study_table(args.dir, obstacles, args.inflate))
    print(text, end="")
    if args.md:
        pathlib.Path(args.md).write_text(text)


if __name__ == "__main__":
    main()
