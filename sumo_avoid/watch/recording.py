"""A finished run read back from its folder (``sumo-avoid run --out DIR``, a batch's run folder): the
tables and files :mod:`sumo_avoid.runs.outputs` wrote, as one frozen :class:`Recording`.

A folder that is no run folder is refused with :class:`~sumo_avoid.core.config.ScenarioError` naming it
(the command line prints one line and exits with code 2)."""
from __future__ import annotations

import dataclasses
import json
import pathlib

import pandas as pd

from sumo_avoid.core.config import ScenarioError


@dataclasses.dataclass(frozen=True)
class Recording:
    run_dir: pathlib.Path
    traj: pd.DataFrame  # trajectories.csv: one row per vehicle per recorded step
    persons: pd.DataFrame | None  # persons.csv, same columns
    metrics: dict  # metrics.json
    net_file: pathlib.Path | None  # from replay.json (or the ledger's net_file); None: no net known
    step_s: float
    egos: tuple[str, ...]
    signals: pd.DataFrame | None  # signals.csv: time_s, tls, state (a row per change)
    detections: pd.DataFrame | None  # detections.csv (radar runs with log_detections)
    ssm: pd.DataFrame | None  # ssm_conflicts.csv

    @property
    def times_s(self):
        """The recorded step times, sorted."""
        return sorted(set(self.traj["time_s"].round(6)))

    @property
    def title(self) -> str:
        m = self.metrics
        return f"{m.get('scenario')} · {m.get('controller')} · seed {m.get('seed')}"


#: The columns the viewers read from each of a run's tables (a table without them is not a run's).
COLUMNS = {"trajectories.csv": ("step", "time_s", "id", "is_ego", "x", "y", "heading", "length", "width"),
           "persons.csv": ("step", "time_s", "id", "x", "y", "heading", "length", "width"),
           "signals.csv": ("time_s", "tls", "state"), "detections.csv": ("time_s", "ego", "x", "y"),
           "ssm_conflicts.csv": ("ego", "foe", "begin_s")}


def _csv(path: pathlib.Path) -> pd.DataFrame | None:
    if not path.is_file() or path.stat().st_size == 0:
        return None
    try:
        table = pd.read_csv(path, dtype={"id": str, "ego": str, "foe": str, "tls": str, "state": str, "target": str})
    except (OSError, ValueError) as e:
        raise ScenarioError(str(path), "<file>", f"a table written by a run ({e})", show_got=False) from None
    missing = [c for c in COLUMNS.get(path.name, ()) if c not in table.columns]
    if missing:
        raise ScenarioError(str(path), "<file>", f"a table written by a run (no column {', '.join(missing)})",
                            show_got=False)
    return table


def load(run_dir, flag: str = "RUN_DIR", net_file=None) -> Recording:
    """The run in ``run_dir``; ``net_file`` overrides the net replay.json names (a ledger's row)."""
    d = pathlib.Path(run_dir)
    if not d.is_dir():
        raise ScenarioError(str(d), flag, "a run folder (no such folder)", show_got=False)
    if not (d / "trajectories.csv").is_file() or not (d / "metrics.json").is_file():
        raise ScenarioError(str(d), flag, "a run folder with trajectories.csv and metrics.json "
                            "(written by sumo-avoid run)", show_got=False)
    try:
        metrics = json.loads((d / "metrics.json").read_text())
        info = json.loads((d / "replay.json").read_text()) if (d / "replay.json").is_file() else {}
    except (OSError, ValueError) as e:
        raise ScenarioError(str(d), flag, f"a run folder whose JSON files read ({e})", show_got=False) from None
    traj = _csv(d / "trajectories.csv")
    if traj is None or traj.empty:
        raise ScenarioError(str(d / "trajectories.csv"), "<file>", "a recording with rows", show_got=False)
    traj["id"] = traj["id"].astype(str)
    traj["is_ego"] = traj["is_ego"].astype(str).str.lower().isin(("true", "1"))
    net = net_file or info.get("net_file")
    net = pathlib.Path(net) if net and pathlib.Path(net).is_file() else None
    egos = tuple(info.get("egos") or sorted(traj.loc[traj["is_ego"], "id"].unique()))
    step = float(info.get("step_s") or metrics.get("step_s") or 0.1)
    return Recording(d, traj, _csv(d / "persons.csv"), metrics, net, step, egos, _csv(d / "signals.csv"),
                     _csv(d / "detections.csv"), _csv(d / "ssm_conflicts.csv"))


def at_time(table: pd.DataFrame, t_s: float) -> pd.DataFrame:
    """The rows of the recorded step at or just before ``t_s`` (the first step if ``t_s`` is earlier)."""
    times = table["time_s"].to_numpy(float)
    before = times[times <= t_s + 1e-9]
    t = before.max() if len(before) else times.min()
    return table[abs(times - t) < 1e-9]
