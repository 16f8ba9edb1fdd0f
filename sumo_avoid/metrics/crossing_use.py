"""Pedestrian crossings from the recording (SPEC §6), whatever the rules layer did:

* ``crossing_violations``: each time an ego's front bumper enters a crossing its link must give way
  at (:attr:`~sumo_avoid.road.crossings.CrossingLink.gives_way`, while the crossing is the people's:
  unsignalised or their green) with a person on it or about to step onto it
  (:func:`~sumo_avoid.road.crossings.persons_at`, from the persons recorded at the step before; one
  walking towards the ego's stretch of it only if, at its speed, it gets there before the ego's rear has
  left the crossing, as recorded: SUMO's drivers go when the people reach the crossing after they have
  passed, and so does the rules layer over consecutive crossings), and
  each crossing an ego came to stand on (slower than ``[layers.traffic]`` stop_speed_mps with its
  footprint's length over the crossing's span on the path) while its people may cross (unsignalised, or
  their green): the ego blocks it. Standing on it only through their red (a left turn waiting in a
  junction whose crossing lies at its entry, as SUMO's drivers wait) is an event, not a violation;
* ``crossing_events``: every entry into a crossing the ego gives way at, judged (ego, crossing, time,
  the persons on it or stepping onto it, violation), and every standing on a crossing.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.rules import _ego_tracks, _signals_at
from sumo_avoid.road.crossings import people_may_cross, persons_at
from sumo_avoid.road.yielding import first_crossing
from sumo_avoid.rollout.result import RunResult


def crossing_events(run: RunResult) -> list[dict]:
    if not run.tasks:
        return []
    rules = run.scenario.table("layers.traffic")
    stand = rules.stop_speed_mps
    persons = run.persons if run.persons is not None else None
    by_step = persons.groupby("step").indices if persons is not None and len(persons) else {}
    out = []
    for vid, task, ego, s in _ego_tracks(run, lambda lk: bool(lk.crossings)):
        steps, t, v = ego["step"].to_numpy(), ego["time_s"].to_numpy(), np.abs(ego["speed"].to_numpy(float))
        length, half = float(ego["length"].iloc[0]), 0.5 * float(ego["width"].iloc[0]) + rules.crossing_margin_m
        for c in (c for lk in task.links for c in lk.crossings):
            k = first_crossing(s, c.s_enter_m)
            if k >= 0 and c.gives_way and people_may_cross(c, _signals_at(run.signals, t[k])):
                rows = by_step.get(steps[k], [])
                who = []
                if len(rows):
                    p = persons.iloc[rows]
                    # a person walking towards the ego's stretch counts if it gets there before the ego
                    # (its rear) has left the crossing, as the recording shows the ego leave
                    gone = np.flatnonzero(s[k + 1:] - length >= c.s_exit_m)
                    horizon = float(t[k + 1 + gone[0]] - t[k]) if len(gone) else np.inf
                    on = persons_at(c, p["lane"].fillna("").to_numpy(), p[["x", "y"]].to_numpy(float),
                                    p[["vx", "vy"]].to_numpy(float), half, rules.crossing_gap_m, horizon)
                    who = sorted(p["id"].astype(str).to_numpy()[on].tolist())
                out.append({"ego": vid, "crossing": c.crossing, "time_s": float(t[k + 1]), "persons": who,
                            "kind": "entered", "violation": bool(who)})
            over = np.flatnonzero((s > c.s_enter_m) & (s - length < c.s_exit_m) & (v < stand))
            if len(over):
                # blocking it while its people may cross (unsignalised, or their green) is the violation;
                # standing on it through their red (a turn waiting in a small junction) is listed, not counted
                # an unsignalised crossing is always its people's; a signalised one: the light at each step
                open_ = over[0] if not c.tls else next(
                    (j for j in over if people_may_cross(c, _signals_at(run.signals, t[j]))), None)
                j = int(over[0] if open_ is None else open_)
                open_ = open_ is not None
                out.append({"ego": vid, "crossing": c.crossing, "time_s": float(t[j]), "persons": [],
                            "kind": "stood on it" if open_ else "stood on it at its people's red",
                            "violation": bool(open_)})
    return out


class CrossingViolations(Metric):
    """Crossings an ego entered while a person had the right of way on it, or stood on."""

    keys = Keys(("crossing_violations",), nested=("crossing_events",))

    def compute(self, run: RunResult) -> dict:
        ev = crossing_events(run)
        return {"crossing_violations": sum(e["violation"] for e in ev), "crossing_events": ev}
