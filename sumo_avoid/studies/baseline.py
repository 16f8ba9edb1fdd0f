"""``travel_time_ratio``: a run's time to goal against SUMO's own driver on the same scenario and seed.

The baseline of a run is the ``done`` ledger row of controller ``sumo`` (SUMO's driver,
:mod:`sumo_avoid.control.sumo_driver`) with the same scenario file, the same seed and the same
overrides once those that cannot change a run SUMO drives are left out (the controller, sensor,
layers, actuator, cruise speed, every ``[controllers.*]``, ``[sensors.*]``, ``[layers.*]``,
``[actuators.*]`` key and ``output.*``): ``travel_time_ratio = time_to_goal_s / baseline
time_to_goal_s``. The baseline's own row reads 1.

The ratio is empty (NaN; "n/a" in reports, a failed criterion in a suite) — never a number made up —
when the ledger holds no such baseline, when the baseline or the run did not reach its goal
(``time_to_goal_s`` null: a run that never arrives has no finite ratio), or the baseline's time is 0.
Several matching baselines (they differ only in overrides SUMO's driver ignores, so they drive
alike) give the first by run key. ``time_to_goal_s`` of a run with several egos is the slowest
ego's, so the ratio compares the slowest egos.
"""
from __future__ import annotations

import json
import math

import pandas as pd

from sumo_avoid.core.types import Keys

BASELINE = "sumo"  # the controller whose runs are the baselines
COLUMN = "travel_time_ratio"
KEYS = Keys((COLUMN,))  # what a ledger row gains: a number per run (suite criteria may name it)
_IGNORED = ("ego.controller", "ego.sensor", "ego.layers", "ego.actuator", "ego.cruise_speed_mps")
_IGNORED_TABLES = ("controllers.", "sensors.", "layers.", "actuators.", "output.")


def _setting(overrides) -> tuple[str, ...]:
    """The overrides (ledger JSON list of KEY=VALUE) that can change a run SUMO's driver drives, sorted."""
    try:
        items = json.loads(overrides) if isinstance(overrides, str) else []
    except ValueError:
        items = []
    out = []
    for item in items if isinstance(items, list) else []:
        key, _, value = str(item).partition("=")
        key = key.strip()
        if key not in _IGNORED and not key.startswith(_IGNORED_TABLES):
            out.append(f"{key}={value.strip()}")
    return tuple(sorted(out))


def _time(v) -> float:
    try:
        t = float(v)
    except (TypeError, ValueError):
        return math.nan
    return t if math.isfinite(t) else math.nan


def with_travel_time_ratio(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` (ledger rows) with the column ``travel_time_ratio`` (float, NaN where there is none)."""
    if df.empty or "controller" not in df:
        return df.assign(**{COLUMN: pd.Series(dtype=float, index=df.index)})
    where = df["scenario_path"] if "scenario_path" in df else pd.Series(None, index=df.index)
    where = where.where(where.notna(), df.get("scenario"))
    seed = df["seed"] if "seed" in df else pd.Series(None, index=df.index)
    setting = df["overrides"].map(_setting) if "overrides" in df else pd.Series([()] * len(df), index=df.index)
    times = df["time_to_goal_s"].map(_time) if "time_to_goal_s" in df else pd.Series(math.nan, index=df.index)
    done = df["status"] == "done" if "status" in df else pd.Series(True, index=df.index)
    match = pd.Series(list(zip(where, seed, setting)), index=df.index)
    base: dict = {}
    order = df["key"].astype(str).sort_values().index if "key" in df else df.index
    for i in order:
        if df.at[i, "controller"] == BASELINE and done[i]:
            base.setdefault(match[i], times[i])
    ratio = [times[i] / base[match[i]] if done[i] and base.get(match[i], 0) > 0 else math.nan for i in df.index]
    return df.assign(**{COLUMN: pd.Series(ratio, index=df.index, dtype=float)})
