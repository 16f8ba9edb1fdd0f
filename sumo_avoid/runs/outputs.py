"""The files of one finished run: metrics.json, timings.json, trajectories.csv, persons.csv (when
the run had persons outside vehicles; the same columns), the plug-ins' tables (e.g. detections.csv), the plots
(:func:`sumo_avoid.runs.declared.plot_names`), and what watching the run needs besides them (``sumo-avoid
replay``, ``report RUN_DIR``): ``replay.json`` (its net file, step, egos, goals and road users' SUMO classes)
and ``signals.csv`` (the traffic lights' recorded states, a row per change; runs with signals).

``metrics.json`` holds only simulation results (no wall-clock fields), written with sorted keys,
so the same scenario and seed give a byte-identical file. Timings go to ``timings.json``.
"""
from __future__ import annotations

import json
import pathlib

from sumo_avoid.core.output_error import writing
from sumo_avoid.metrics import clean, compute
from sumo_avoid.plots import PLOTS
from sumo_avoid.rollout.result import RunResult
from sumo_avoid.runs.declared import metric_names, plot_names


def run_metrics(res: RunResult) -> dict:
    return compute(res, metric_names(res.scenario))


def timings(res: RunResult) -> dict:
    """The run's wall-clock timings, plus a planner's plan times (mean and max over its plans, ms)."""
    out = dict(res.timings)
    plans = res.tables.get("plans")
    if plans is not None and len(plans):
        out.update(plan_ms_mean=float(plans["plan_ms"].mean()), plan_ms_max=float(plans["plan_ms"].max()))
    return out


def write_outputs(res: RunResult, out_dir: pathlib.Path, plots: bool = True) -> dict:
    """Write the run's files into ``out_dir`` (made if its parent exists: a vanished folder is not made
    again); raises OutputError naming the file that cannot be written (core/output_error.py)."""
    m = run_metrics(res)
    with writing(out_dir):
        out_dir.mkdir(exist_ok=True)
    with writing(out_dir / "metrics.json"):
        (out_dir / "metrics.json").write_text(json.dumps(m, indent=2, sort_keys=True) + "\n")
    with writing(out_dir / "timings.json"):
        (out_dir / "timings.json").write_text(json.dumps(clean(timings(res)), indent=2, sort_keys=True) + "\n")
    tables = {"trajectories": res.traj}
    if res.persons is not None and len(res.persons):  # pedestrians (and riders while they walk)
        tables["persons"] = res.persons
    for name, table in {**tables, **res.tables}.items():
        with writing(out_dir / f"{name}.csv"):
            table.to_csv(out_dir / f"{name}.csv", index=False)
    write_replay_files(res, out_dir)
    if plots:
        title = (f"{m['scenario']} · {m['controller']} · seed {m['seed']} · collisions {m['collisions']}"
                 f" · goal {'reached' if m['goal_reached'] else 'NOT reached'}")
        for name in plot_names(res.scenario):
            with writing(out_dir):
                PLOTS[name].factory(res, m, out_dir, title)
    return m


def replay_info(res: RunResult) -> dict:
    """What a replay needs that the tables do not hold: the net, the step, the egos, their goals, the classes."""
    scn = res.scenario
    return {"net_file": str(pathlib.Path(scn.net_file).resolve()) if getattr(scn, "net_file", None) else None,
            "scenario_file": str(pathlib.Path(scn.path).resolve()), "step_s": scn.spec.sim.step_s,
            "egos": sorted(res.goals) or sorted(res.traj.loc[res.traj["is_ego"].astype(bool), "id"].unique()),
            "goals": {k: [float(v) for v in xy] for k, xy in sorted(res.goals.items())},
            "classes": dict(sorted(res.classes.items()))}


def write_replay_files(res: RunResult, out_dir: pathlib.Path) -> None:
    """``replay.json`` and (with signals) ``signals.csv``: new files only, the others stay byte for byte."""
    with writing(out_dir / "replay.json"):
        (out_dir / "replay.json").write_text(json.dumps(replay_info(res), indent=1, sort_keys=True) + "\n")
    if res.signals is not None and len(res.signals):
        with writing(out_dir / "signals.csv"):
            res.signals.to_csv(out_dir / "signals.csv", index=False)
