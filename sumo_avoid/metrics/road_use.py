"""How far the egos drove where they should not: against a lane's direction, and off the road;
and how far they backed up.

Each ego's path is cut into its recorded steps: the segment from one row to the ego's next row,
whose length (m) counts wholly when its midpoint qualifies, with the heading of its first row.

* ``wrong_way_m``: the midpoint is inside a normal lane's polygon (nearest centre line of those
  holding it) and outside every junction shape, and the car's **heading** is more than 90° from
  that lane's direction there (:meth:`sumo_avoid.road.lane_index.LaneIndex.against`): it faces the
  lane's traffic (a ghost driver), whichever way it moves. None in an arena (its roads only give
  SUMO lanes to map the flock onto). Documented choice: backing up in one's own lane faces the
  lane's direction and is not wrong-way driving (it is ``reverse_m``): counted here, an escape
  manoeuvre would look like driving against traffic.
* ``reverse_m``: the motion is more than 90° from the heading (backing up), anywhere.
* ``off_road_m``: the midpoint is outside the drivable area of the ego's vehicle class
  (``Road.outside_distance`` > 0; the lanes open to it, internal ones included, and junction shapes),
  or in an arena outside its walls or inside an obstacle.
  φ_wall measures how far the footprint sticks out; this measures how long the centre was out.

* ``forbidden_lane_m``: the midpoint is inside a normal lane (nearest centre line of those holding it,
  outside every junction shape) that the net's permissions close to the ego's vehicle class -- a
  sidewalk, a bike lane, a bus lane for a car -- read from the net, not from where SUMO maps the ego.
  None in an arena.

* ``speeding_m``: the midpoint is inside a normal lane (outside every junction shape) and the ego's
  recorded speed at the segment's first row exceeds the highest speed limit of the normal lanes holding
  it by more than ``SPEEDING_TOL_MPS`` (1 km/h). The rules layer enforces limits only with
  ``[layers.traffic] speed_factor`` set; SUMO's own drivers drive at their vType's speedFactor
  (default: mean 1.0, deviation 0.1), so they exceed limits too. None in an arena.

All are summed over the egos (m), 0.0 when no ego ever moved.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.ego_rows import EgoRows
from sumo_avoid.metrics.standard import ego_class, ego_rows
from sumo_avoid.road.walls import outside_distance as arena_outside_distance
from sumo_avoid.rollout.result import RunResult

SPEEDING_TOL_MPS = 1.0 / 3.6  # speeding is more than 1 km/h over the limit


def ego_segments(traj: pd.DataFrame, egos: EgoRows | None = None, with_ids: bool = False) -> tuple:
    """Every ego's consecutive rows (by step) as segments: (K,2) midpoints, (K,2) displacements, m,
    and (K,2) unit heading vectors of each segment's first row (and, ``with_ids``, (K,) its ego's id and
    (K,) its first row's speed, m/s); segments of zero length are left out."""
    egos = EgoRows.of(traj) if egos is None else egos
    e = egos.table
    o = egos.by_id()
    code = egos.code[o]
    p = e[["x", "y"]].to_numpy(float)[o]
    d = np.diff(p, axis=0)
    keep = (code[1:] == code[:-1]) & (np.hypot(d[:, 0], d[:, 1]) > 0)
    mid = 0.5 * (p[:-1] + p[1:])
    h = e["heading"].to_numpy(float)[o][:-1]
    out = mid[keep], d[keep], np.column_stack([np.cos(h), np.sin(h)])[keep]
    if not with_ids:
        return out
    return (*out, egos.ids[code[:-1][keep]], np.abs(e["speed"].to_numpy(float)[o][:-1][keep]))


def forbidden(road, mid: np.ndarray, vclass: np.ndarray) -> np.ndarray:
    """(K,) True where a midpoint lies in a normal lane (outside every junction shape) and *every*
    normal lane holding it is closed by the net to the class of its ego (SUMO's ``allow``/``disallow``,
    :attr:`Road.elements`). Where a net lays two lanes over each other (a street-running tram's track
    on the car lane, Braunschweig), a car in its own lane is not on the track's lane."""
    if not len(mid):
        return np.zeros(0, bool)
    p, q = road.lanes.holding(mid)
    lanes, ids = road.elements.lanes, road.lanes.ids
    vclass = np.asarray(vclass, dtype=object)
    open_ = np.array([bool(vclass[i]) and vclass[i] in lanes[ids[k]].allow for i, k in zip(p, q)], bool)
    held, fine = np.zeros(len(mid), bool), np.zeros(len(mid), bool)
    held[p] = True
    fine[p[open_]] = True
    classed = np.array([bool(v) for v in vclass], bool)
    return held & ~fine & classed & ~road.lanes.in_junction(mid)


def over_limit(road, mid: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """(K,) True where a midpoint lies in a normal lane (outside every junction shape: internal lanes
    carry netconvert's turning speeds, no legal limit) and the speed exceeds by more than
    :data:`SPEEDING_TOL_MPS` the highest limit of the normal lanes holding it."""
    if not len(mid):
        return np.zeros(0, bool)
    p, q = road.lanes.holding(mid)
    lanes, ids = road.elements.lanes, road.lanes.ids
    limit = np.full(len(mid), -np.inf)
    np.maximum.at(limit, p, np.array([lanes[ids[k]].speed_mps for k in q], float))
    return np.isfinite(limit) & (speed > limit + SPEEDING_TOL_MPS) & ~road.lanes.in_junction(mid)


def road_use(run: RunResult) -> dict:
    mid, d, hd, who, speed = ego_segments(run.traj, ego_rows(run), with_ids=True)
    length = np.hypot(d[:, 0], d[:, 1])
    reverse_m = float(length[np.einsum("ij,ij->i", hd, d) < 0].sum())
    scene = run.scene
    if scene.walls is None:
        vclass = np.array([ego_class(run, v) or "" for v in who], dtype=object)
        out = np.zeros(len(mid), bool)
        for vc in np.unique(vclass):
            rows = vclass == vc
            out[rows] = run.road.outside_distance(mid[rows], vc or None) > 0
        wrong = run.road.lanes.against(mid, hd) if len(mid) else np.zeros(0, bool)
        wrong_m = float(length[wrong].sum())
        banned_m = float(length[forbidden(run.road, mid, vclass)].sum())
        speeding_m = float(length[over_limit(run.road, mid, speed)].sum())
    else:
        out = arena_outside_distance(mid, scene.walls, scene.obstacles) > 0
        wrong_m = banned_m = speeding_m = None
    return {"wrong_way_m": wrong_m, "off_road_m": float(length[out].sum()), "reverse_m": reverse_m,
            "forbidden_lane_m": banned_m, "speeding_m": speeding_m}



class RoadUse(Metric):
    """wrong_way_m, off_road_m, reverse_m, forbidden_lane_m, speeding_m: metres the egos drove facing a
    lane's traffic, off the road, backwards, on lanes closed to their class, and above the speed limit."""

    keys = Keys(("wrong_way_m", "off_road_m", "reverse_m", "forbidden_lane_m", "speeding_m"))

    def compute(self, run: RunResult) -> dict:
        return road_use(run)
