"""Truth vs radar on the same seeds, side by side.

    python -m sumo_avoid.studies.radar_study scenarios/overtaking.toml --seeds 1-10 [--set KEY=VALUE ...]

Runs the scenario once with ``ego.sensor = "truth"`` and once with ``"radar"`` per seed (same
controller, same safety setting) and prints one row per seed plus totals; ``--csv`` writes them.
"""
from __future__ import annotations

import argparse
import pathlib

import pandas as pd

from sumo_avoid.runs import outputs as evaluate
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario

KEYS = ["goal_reached", "collisions", "min_gap_m", "time_to_goal_s", "mean_speed_mps", "radar_warnings",
        "radar_brakes", "min_danger_time_s"]


def seeds(text: str) -> list[int]:
    out = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def study(path, seed_list, overrides=()) -> pd.DataFrame:
    rows = []
    for seed in seed_list:
        row = {"seed": seed}
        for sensor in ("truth", "radar"):
            scn = scenario.load(path, [*overrides, f'ego.sensor="{sensor}"'], seed=seed)
            m = evaluate.run_metrics(runner.run(scn))
            row.update({f"{sensor}_{k}": m.get(k) for k in KEYS if sensor == "radar" or not k.startswith("radar")
                        and k != "min_danger_time_s"})
        rows.append(row)
    return pd.DataFrame(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", type=pathlib.Path)
    ap.add_argument("--seeds", default="1-10")
    ap.add_argument("--set", dest="overrides", action="append", default=[])
    ap.add_argument("--csv", type=pathlib.Path, default=None)
    a = ap.parse_args(argv)
    df = study(a.scenario, seeds(a.seeds), a.overrides)
    with pd.option_context("display.width", 200, "display.max_columns", 30):
        print(df.to_string(index=False, float_format=lambda x: f"{x:.2f}"))
    for s in ("truth", "radar"):
        print(f"{s:5s}: goal {int(df[f'{s}_goal_reached'].sum())}/{len(df)}  collisions {int(df[f'{s}_collisions'].sum())}"
              f"  min gap {df[f'{s}_min_gap_m'].min():.2f} m  mean time to goal {df[f'{s}_time_to_goal_s'].mean():.1f} s")
    if a.csv:
        df.to_csv(a.csv, index=False)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
