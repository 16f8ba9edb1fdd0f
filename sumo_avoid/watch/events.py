"""A run's events, each a point in time and space with a label: collisions, rule violations
(signals, yielding, stop signs, crossings), SSM conflicts (SUMO's device). (APF-SA's escapes and a planner's replans are counters in metrics.json,
without a time: they are not events here.)"""
from __future__ import annotations

import dataclasses

import numpy as np

from sumo_avoid.watch.recording import Recording

# metrics.json list -> (kind, whether only its entries with "violation" true are events)
LISTS = {"collision_events": ("collision", False), "signal_crossings": ("red light", True),
         "yield_crossings": ("yield violation", True), "stop_crossings": ("stop sign", True),
         "crossing_events": ("crossing violation", True)}


@dataclasses.dataclass(frozen=True)
class Event:
    time_s: float
    kind: str  # collision | red light | yield violation | stop sign | crossing violation | ssm conflict
    label: str  # time, what, with whom
    x_m: float
    y_m: float
    ego: str
    other: str


def _ego_xy(rec: Recording, ego: str, t_s: float) -> tuple[float, float]:
    g = rec.traj[rec.traj["id"] == ego]
    if g.empty:
        return float("nan"), float("nan")
    k = int(np.argmin(np.abs(g["time_s"].to_numpy(float) - t_s)))
    return float(g["x"].iloc[k]), float(g["y"].iloc[k])


def _other(e: dict) -> str:
    for key in ("b", "foe", "persons", "junction", "crossing", "tls"):
        v = e.get(key)
        if v:
            return ", ".join(map(str, v)) if isinstance(v, list) else str(v)
    return ""


def _how(e: dict) -> str:
    """How a contact happened (metrics.contacts), e.g. " (ego stopped, 5.1 m/s)"; "" for other events."""
    if not e.get("kind"):
        return ""
    speed = e.get("impact_speed_mps")
    jumped = ", it jumped" if e.get("other_jumped") else ""
    return f" ({str(e['kind']).replace('_', ' ')}" + (f", {speed:.1f} m/s" if speed is not None else "") + f"{jumped})"


def events(rec: Recording) -> list[Event]:
    """Every event of the run, sorted by time."""
    out = []
    for key, (kind, only_violations) in LISTS.items():
        for e in rec.metrics.get(key) or []:
            if not isinstance(e, dict) or "time_s" not in e or (only_violations and not e.get("violation")):
                continue
            ego = str(e.get("ego") or e.get("a") or (rec.egos[0] if rec.egos else ""))
            t = float(e["time_s"])
            x, y = (float(e["x"]), float(e["y"])) if "x" in e and "y" in e else _ego_xy(rec, ego, t)
            other = _other(e) if "a" not in e else str(e["b"] if str(e["a"]) == ego else e["a"])
            out.append(Event(t, kind, f"{t:.1f} s {kind}{_how(e)}: {ego}" + (f" with {other}" if other else ""),
                             x, y, ego, other))
    if rec.ssm is not None:
        for r in rec.ssm.to_dict(orient="records"):
            t = r.get("ttc_time_s") if r.get("ttc_time_s") == r.get("ttc_time_s") else r.get("begin_s")
            x, y = r.get("ttc_x"), r.get("ttc_y")
            if x != x or y != y or x is None:  # NaN: SUMO wrote NA
                x, y = _ego_xy(rec, str(r["ego"]), float(t))
            ttc = r.get("ttc_s")
            what = f"ssm conflict (TTC {ttc:.2f} s)" if ttc == ttc and ttc is not None else "ssm conflict"
            out.append(Event(float(t), "ssm conflict", f"{float(t):.1f} s {what}: {r['ego']} with {r['foe']}",
                             float(x), float(y), str(r["ego"]), str(r["foe"])))
    return sorted(out, key=lambda e: (e.time_s, e.kind))
