"""How each contact happened, from the recording: who was moving, how fast they met, and whether the other
party arrived by a jump (a study of who hits whom needs more than a count).

For each contact event (:func:`sumo_avoid.metrics.standard.all_collision_events`, its first step), with the
ego the party that is an ego (for two egos, ``a``) and the other the other party:

* ``ego_speed_mps``, ``other_speed_mps``: their recorded speeds at that step.
* ``impact_speed_mps``: the speed of one relative to the other there, ``|v_ego - v_other|`` (recorded
  velocity vectors): the closing speed of the contact, the quantity injury-risk curves are drawn over.
* ``kind``: the classification of the nuPlan devkit's at-fault collision metric
  (``nuplan/planning/metrics/utils/collision_utils.py`` CollisionType, ``_get_collision_type`` of
  ``no_ego_at_fault_collisions.py``), tested in this order:
  ``ego_stopped`` (ego speed <= :data:`STOPPED_MPS`), ``other_stopped`` (the other's speed <= it),
  ``rear`` (the other's centre lies more than :data:`REAR_DEG` off the ego's heading, seen from the ego's
  centre; nuPlan measures from the rear axle, which the recording does not have), ``front`` (the other's
  footprint, or a person's disc, touches the ego's front face), ``lateral`` (the rest).
* ``other_jumped``: within :data:`JUMP_WINDOW_S` before the contact, the other party was not where its motion
  could have brought it: over a recorded step it moved farther than its recorded speeds allow (the larger of
  the two, times the interval) plus :data:`JUMP_SLACK_M`, or it was not recorded a step before (it appeared,
  or reappeared). SUMO moves people across a junction without walking areas in one step (a pedestrian 15.7 m
  on, onto a car standing at the stop line: the unseen Lyon net, reports/cities), and inserts vehicles where
  they depart.

Nothing here removes a contact from a count: ``collisions`` and ``vru_collisions`` count every one; these
fields say how each happened.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
from shapely.geometry import LineString, Point, Polygon

from sumo_avoid.core.geometry import footprint_corners
from sumo_avoid.metrics.vru import person_radius

STOPPED_MPS = 0.05  # nuPlan's stopped_speed_threshold, m/s
REAR_DEG = 150.0  # nuPlan's is_agent_behind angle tolerance, degrees
JUMP_SLACK_M = 1.0  # beyond the distance its speeds allow, m
JUMP_WINDOW_S = 1.0  # a jump this long before the contact counts, s
FIELDS = ["ego", "ego_speed_mps", "other_speed_mps", "impact_speed_mps", "kind", "other_jumped"]
_COLS = ["step", "time_s", "id", "x", "y", "vx", "vy", "speed", "heading", "length", "width"]


def describe(events: pd.DataFrame, traj: pd.DataFrame, persons: pd.DataFrame | None, egos: set,
             with_person: np.ndarray | None = None) -> pd.DataFrame:
    """``events`` with the columns of :data:`FIELDS` added (one row per event, same order). ``with_person``:
    per event, is the other party a person (SUMO keeps persons' and vehicles' ids apart, so one id may name
    both); by default, an id found among the recorded persons is one."""
    if events.empty:
        return events.assign(**{f: pd.Series(dtype=object) for f in FIELDS})
    a, b = events["a"].astype(str).to_numpy(), events["b"].astype(str).to_numpy()
    ego = np.where(np.isin(a, list(egos)), a, b)
    other = np.where(ego == a, b, a)
    if with_person is None:
        people = set() if persons is None or persons.empty else set(persons["id"].astype(str))
        with_person = np.array([o in people for o in other], bool)
    wanted = set(ego) | set(other)
    rows = ({}, {})  # vehicles', persons': id -> its recorded rows, by step
    for table, into in ((traj, rows[0]), (persons, rows[1])):
        if table is None or table.empty:
            continue
        t = table.loc[table["id"].astype(str).isin(wanted), _COLS]
        into.update((vid, g.set_index("step").sort_index()) for vid, g in t.groupby(t["id"].astype(str), sort=False))
    start = int(traj["step"].min())
    out = [_one(rows[0][e], rows[int(p)][o], int(step), bool(p), start)
           for e, o, step, p in zip(ego, other, events["step"], with_person)]
    described = pd.DataFrame(out, columns=FIELDS[1:], index=events.index)
    return events.assign(ego=ego, **{c: described[c] for c in FIELDS[1:]})


def _one(e: pd.DataFrame, o: pd.DataFrame, step: int, person: bool, start: int) -> tuple:
    er, orow = e.loc[step], o.loc[step]
    v_e, v_o = np.array([er["vx"], er["vy"]], float), np.array([orow["vx"], orow["vy"]], float)
    impact = float(np.hypot(*(v_e - v_o)))
    return (float(er["speed"]), float(orow["speed"]), impact, _kind(er, orow, person),
            _jumped(o, step, float(er["time_s"]), start))


def _kind(er, orow, person: bool) -> str:
    if float(er["speed"]) <= STOPPED_MPS:
        return "ego_stopped"
    if float(orow["speed"]) <= STOPPED_MPS:
        return "other_stopped"
    h = float(er["heading"])
    to_other = np.array([orow["x"] - er["x"], orow["y"] - er["y"]], float)
    if np.hypot(*to_other) > 0.0:
        cos = (to_other @ np.array([np.cos(h), np.sin(h)])) / np.hypot(*to_other)
        if np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) > REAR_DEG:
            return "rear"
    c = footprint_corners(np.array([[er["x"], er["y"]]]), h, er["length"], er["width"])[0]
    front = LineString([c[0], c[1]])  # front-right to front-left
    if person:
        hit = front.distance(Point(orow["x"], orow["y"])) <= float(person_radius(orow["length"], orow["width"]))
    else:
        oc = footprint_corners(np.array([[orow["x"], orow["y"]]]), orow["heading"], orow["length"], orow["width"])[0]
        hit = front.intersects(Polygon(oc))
    return "front" if hit else "lateral"


def _jumped(o: pd.DataFrame, step: int, t: float, start: int) -> bool:
    """Did ``o`` arrive by a jump within :data:`JUMP_WINDOW_S` before ``step`` (at time ``t``; ``start``: the
    run's first recorded step)?"""
    first = o.index[(o.index <= step) & (o["time_s"].to_numpy() >= t - JUMP_WINDOW_S)][0]
    before = o.index[o.index < first]
    if first > start and (before.empty or before[-1] != first - 1):
        return True  # not recorded the step before: it appeared (or reappeared) within the window
    rows = o.loc[(o.index >= (before[-1] if len(before) else first)) & (o.index <= step)]
    if np.any(np.diff(rows.index.to_numpy()) != 1):
        return True  # absent for a step within the window
    x, y, v, tt = (rows[c].to_numpy(float) for c in ("x", "y", "speed", "time_s"))
    moved = np.hypot(np.diff(x), np.diff(y))
    return bool(np.any(moved > np.maximum(v[1:], v[:-1]) * np.diff(tt) + JUMP_SLACK_M))
