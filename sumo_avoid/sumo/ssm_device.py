"""SUMO's surrogate-safety-measure (SSM) device on the egos: its command-line options and its XML
output read back into one table per run (SUMO docs: Simulation/Output/SSM_Device).

Only the egos carry the device; it measures TTC, DRAC and PET against
every vehicle within ``range_m`` and logs an encounter as a *conflict* (one ``<conflict>`` element)
when one of its measures crosses its threshold (TTC or PET below, DRAC above). With
``--device.ssm.trajectories false`` each conflict carries only the extremes: ``minTTC``,
``maxDRAC`` and ``PET``, each with time, conflict point, encounter type code and value ("NA" when
SUMO could not compute it, e.g. PET for a car-following encounter). SUMO writes the file as
encounters end and completes it when the simulation closes. Nothing here imports libsumo.

How the egos are equipped: not with ``--device.ssm.explicit``. SUMO reads that list once per
process (``MSDevice::myExplicitIDs`` is static and never cleared): in a process that runs several
simulations through libsumo (tests, benchmarks, ``reproduce``), every later run keeps the first
run's list.
Instead each ego's definition gets the per-vehicle parameter ``has.ssm.device = true``: the route
and additional files that define an ego are copied, so changed, into the run's temporary folder
(:func:`equip`), the others are passed as they are.

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
    """Equip these egos, write to ``file`` (in the run's temporary folder, where :func:`equip` also
    writes its copies)."""

    ego_ids: tuple[str, ...]
    file: pathlib.Path
    params: SsmParams = SsmParams()


EQUIP = ("has.ssm.device", "true")  # the per-vehicle parameter that gives a vehicle the device
EGO_TAGS = ("vehicle", "trip")  # elements defining one named vehicle (a flow's ids are generated)


def equip(files, req: SsmRequest, prefix: str = "") -> list[pathlib.Path]:
    """The files with every ego's definition carrying :data:`EQUIP`: a file defining an ego is
    copied into ``req.file``'s folder (named ``PREFIXk_NAME``) with a ``<param>`` added to the ego's
    element, the others are returned as they are, as is a file that is no readable XML (SUMO then
    reports it). Relative paths inside a copied file would resolve from the temporary folder."""
    out = []
    for k, f in enumerate(files):
        f = pathlib.Path(f)
        try:
            tree = ET.parse(f)
        except (ET.ParseError, OSError):
            out.append(f)
            continue
        egos = [e for e in tree.getroot().iter() if e.tag in EGO_TAGS and e.get("id") in req.ego_ids]
        if not egos:
            out.append(f)
            continue
        for e in egos:
            ET.SubElement(e, "param", key=EQUIP[0], value=EQUIP[1])
        dst = req.file.parent / f"{prefix}{k}_{f.name}"
        tree.write(dst, encoding="UTF-8", xml_declaration=True)
        out.append(dst)
    return out


def ssm_args(req: SsmRequest) -> list[str]:
    """SUMO options for the SSM device of the vehicles :func:`equip` gave one (no other vehicle)."""
    if not req.ego_ids:
        return []
    p = req.params
    return ["--device.ssm.measures", "TTC DRAC PET",
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
