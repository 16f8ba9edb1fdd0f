"""Traffic-rule metrics from the recording (SPEC §5 "Metrics"), whatever the rules layer did (a
run with ``ego.rules = "none"`` is measured the same way).

``red_light_violations``: the ego's front bumper crosses a stop line (between two recorded steps)
while its link shows 'r' / 'u' at the earlier step, or 'y' when, at the onset of that yellow, the
ego could have stopped comfortably (v^2 / (2 b_comf) <= distance to the line, b_comf of the
scenario's ``[rules]``). Details per crossing in ``signal_crossings`` (ego, tls, link, time, state).
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.polyline import polyline_track
from sumo_avoid.metrics.base import Metric
from sumo_avoid.rollout.result import RunResult
from sumo_avoid.safety.rules import RED


def _state_at(sig, tls: str, t: float) -> tuple[str, float]:
    """(state string, time it began) of light ``tls`` at time ``t``."""
    rows = sig[(sig["tls"] == tls) & (sig["time_s"] <= t + 1e-9)]
    if rows.empty:
        return "", -np.inf
    return rows["state"].iloc[-1], float(rows["time_s"].iloc[-1])


def signal_crossings(run: RunResult) -> list[dict]:
    sig = run.signals
    if sig is None or sig.empty or not run.tasks:
        return []
    b = run.scenario.spec.rules.comfort_decel_mps2
    out = []
    traj = run.traj[run.traj["is_ego"]]
    for vid, task in run.tasks.items():
        links = [lk for lk in task.links if lk.tls]
        ego = traj[traj["id"] == vid]
        if not links or len(ego) < 2:
            continue
        h = ego["heading"].to_numpy()
        front = ego[["x", "y"]].to_numpy() + 0.5 * ego["length"].to_numpy()[:, None] * np.column_stack([np.cos(h), np.sin(h)])
        s = polyline_track(task.path, front)
        t, v = ego["time_s"].to_numpy(), ego["speed"].to_numpy()
        for lk in links:
            k = np.flatnonzero((s[:-1] < lk.s_stop_m) & (s[1:] >= lk.s_stop_m))
            if not len(k):
                continue
            k = int(k[0])
            state, since = _state_at(sig, lk.tls, t[k])
            c = state[lk.link_index] if 0 <= lk.link_index < len(state) else ""
            violation = c in RED
            if c == "y":
                j = int(np.clip(np.searchsorted(t, since), 0, k))
                violation = v[j] ** 2 / (2.0 * b) <= lk.s_stop_m - s[j]
            out.append({"ego": vid, "tls": lk.tls, "link_index": lk.link_index, "time_s": float(t[k + 1]),
                        "state": c, "violation": bool(violation)})
    return out


class RuleViolations(Metric):
    def compute(self, run: RunResult) -> dict:
        crossings = signal_crossings(run)
        return {"red_light_violations": sum(c["violation"] for c in crossings),
                "signal_crossings": crossings}
