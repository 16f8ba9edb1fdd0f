"""SUMO's surrogate-safety-measure (SSM) device on the egos: its command-line options and its XML
output read back into one table per run (SUMO docs: Simulation/Output/SSM_Device).

Only the egos carry the device (``--device.ssm.explicit``); it measures TTC, DRAC and PET against
every vehicle within ``range_m`` and logs an encounter as a *conflict* (one ``<conflict>`` element)
when one of its measures crosses its threshold (TTC or PET below, DRAC above). With
``--device.ssm.trajectories false`` each conflict carries only the extremes: ``minTTC``,
``maxDRAC`` and ``PET``, each with time, conflict point, encounter type code and value ("NA" when
SUMO could not compute it, e.g. PET for a car-following encounter). SUMO writes the file as
encounters end and completes it when the simulation closes. Nothing here imports libsumo.

Because only conflicts are logged, a run's extremes are exact only up to the thresholds:
min(threshold, smallest logged minTTC) equals min(threshold, true minimum TTC) (every encounter
whose TTC fell below the threshold is logged), likewise for PET, and max(threshold, largest logged
maxDRAC) for DRAC (:mod:`sumo_avoid.metrics.ssm`).
"""
from __future__ import annotations

import math
import pathlib
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import pandas as pd

MEASURES = (("minTTC", "ttc"), ("maxDRAC", "drac"), ("PET", "pet"))  # XML element -> column stem
UNITS = {"ttc": "s", "drac": "mps2", "pet": "s"}
COLUMNS = ["ego", "foe", "begin_s", "end_s"] + [c for _, m in MEASURES for c in (
    f"{m}_{UNITS[m]}", f"{m}_time_s", f"{m}_x", f"{m}_y", f"{m}_type")]


@dataclass(frozen=True)
class SsmParams:
    """The SSM device's settings (the same for every run; SUMO's defaults are 3 s, 3 m/s², 2 s)."""

    ttc_threshold_s: float = 5.0  # a conflict when TTC falls below, s
    drac_threshold_mps2: float = 1.0  # ... or DRAC exceeds, m/s^2
    pet_threshold_s: float = 3.0  # ... or PET falls below, s
    range_m: float = 50.0  # vehicles within this distance of the ego are traced, m
    extratime_s: float = 5.0  # an encounter is followed this long after it ends (PET needs > 0), s


@dataclass(frozen=True)
class SsmRequest:
    """Equip these egos, write to ``file`` (in the run's temporary folder)."""

    ego_ids: tuple[str, ...]
    file: pathlib.Path
    params: SsmParams = SsmParams()


def ssm_args(req: SsmRequest) -> list[str]:
    """SUMO options equipping the egos (and no other vehicle) with the SSM device."""
    if not req.ego_ids:
        return []
    p = req.params
    return ["--device.ssm.explicit", ",".join(sorted(req.ego_ids)),
            "--device.ssm.measures", "TTC DRAC PET",
            "--device.ssm.thresholds", f"{p.ttc_threshold_s!r} {p.drac_threshold_mps2!r} {p.pet_threshold_s!r}",
            "--device.ssm.range", repr(p.range_m), "--device.ssm.extratime", repr(p.extratime_s),
            "--device.ssm.trajectories", "false", "--device.ssm.file", str(req.file)]


def _num(text) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):  # "NA" or missing
        return math.nan
    return v if math.isfinite(v) else math.nan


def _point(text) -> tuple[float, float]:
    parts = (text or "").split(",")
    return (_num(parts[0]), _num(parts[1])) if len(parts) == 2 else (math.nan, math.nan)


def read_conflicts(path) -> pd.DataFrame:
    """The conflicts of an SSM output file, one row each (columns :data:`COLUMNS`; times s, points m,
    TTC and PET s, DRAC m/s², NaN for "NA", ``*_type`` SUMO's encounter type code), sorted by begin,
    ego, foe. A missing or empty file (no ego ever ran) gives an empty table."""
    path = pathlib.Path(path)
    rows = []
    if path.is_file() and path.stat().st_size > 0:
        for c in ET.parse(path).getroot().iter("conflict"):
            row = {"ego": c.get("ego", ""), "foe": c.get("foe", ""), "begin_s": _num(c.get("begin")),
                   "end_s": _num(c.get("end"))}
            for tag, stem in MEASURES:
                e = c.find(tag)
                get = e.get if e is not None else (lambda _k: None)
                row[f"{stem}_{UNITS[stem]}"] = _num(get("value"))
                row[f"{stem}_time_s"] = _num(get("time"))
                row[f"{stem}_x"], row[f"{stem}_y"] = _point(get("position"))
                row[f"{stem}_type"] = _num(get("type"))
            rows.append(row)
    df = pd.DataFrame(rows, columns=COLUMNS)
    for _, m in MEASURES:
        df[f"{m}_type"] = df[f"{m}_type"].astype("Int64")  # integer codes, <NA> where SUMO wrote NA
    return df.sort_values(["begin_s", "ego", "foe"], kind="stable").reset_index(drop=True)
