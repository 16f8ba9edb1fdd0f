"""The egos and the vulnerable road users (SPEC §6): contacts with persons and the smallest gap to
persons and cyclists, from the recording.

* A person is a disc about its recorded centre, radius half the larger of its SUMO length and width
  (a pedestrian of SUMO's default type: 0.239 m). An ego touches a person when the distance from the
  person's centre to the ego's footprint (oriented rectangle) is at most that radius. One contact
  event per (ego, person) pair and contact episode: a run of consecutive recorded steps with contact,
  as for vehicles (:func:`sumo_avoid.metrics.basic.collision_events`).
* Vulnerable road users (VRU): persons, and vehicles of the classes in :data:`VRU_CLASSES` -- the
  EU ITS Directive 2010/40/EU's "non-motorised road users, such as pedestrians and cyclists, as well
  as motorcyclists and persons with disabilities or reduced mobility", in SUMO's classes. A cyclist is
  a vehicle: its contacts are found by the footprint check of all vehicles, and counted again here.
  (:data:`sumo_avoid.road.elements.VRU_CLASSES`.)
* ``min_gap_vru_m``: the smallest distance between an ego's footprint and a VRU (a person's disc, a
  cyclist's footprint) present at the same step; None when no ego ever shares a step with one.
* Only pairs on one level count (:mod:`sumo_avoid.core.levels`; the recording's ``z``).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid.core.geometry import convex_distance, footprint_corners
from sumo_avoid.core.levels import apart_pairs, same_level
from sumo_avoid.road.elements import VRU_CLASSES

PERSON_EVENT_COLS = ["step", "time_s", "a", "b", "x", "y"]
CONTACT_TOL_M = 1e-9


def person_radius(length, width) -> np.ndarray:
    return 0.5 * np.maximum(np.asarray(length, float), np.asarray(width, float))


def rectangle_point_distance(cx, cy, heading, length, width, px, py) -> np.ndarray:
    """Distance from points (px, py) to oriented rectangles (centre, heading, length x width), 0 inside."""
    dx, dy = np.asarray(px, float) - cx, np.asarray(py, float) - cy
    c, s = np.cos(heading), np.sin(heading)
    along, across = np.abs(c * dx + s * dy), np.abs(-s * dx + c * dy)
    return np.hypot(np.maximum(along - 0.5 * np.asarray(length, float), 0.0),
                    np.maximum(across - 0.5 * np.asarray(width, float), 0.0))


def ego_person_pairs(traj: pd.DataFrame, persons: pd.DataFrame | None, apart=None) -> pd.DataFrame:
    """Every (ego, person) pair present at one recorded step, with the gap between the ego's
    footprint and the person's disc (m, negative = overlap). Columns: step, time_s, ego, person,
    gap_m, x, y (the midpoint of the two centres). Pairs on two levels are left out (heights; with ``apart``,
    ``Road.apart``, also edges crossing without a junction: road.grade)."""
    cols = ["step", "time_s", "ego", "person", "gap_m", "x", "y"]
    if persons is None or persons.empty or traj.empty:
        return pd.DataFrame(columns=cols)
    levels = "z" in traj and "z" in persons  # heights recorded: pairs on one level only (core.levels)
    lanes = bool(apart) and "lane" in traj and "lane" in persons
    ego = traj.loc[traj["is_ego"].astype(bool), ["step", "time_s", "id", "x", "y", "heading", "length", "width"]
                   + (["z"] if levels else []) + (["lane"] if lanes else [])]
    per = persons[["step", "id", "x", "y", "length", "width"] + (["z"] if levels else []) + (["lane"] if lanes else [])]
    m = ego.merge(per, on="step", suffixes=("_e", "_p"))
    if levels:
        m = m[same_level(m["z_e"].to_numpy(float), m["z_p"].to_numpy(float))]
    if lanes:
        m = m[~apart_pairs(apart, m["lane_e"].fillna("").astype(str), m["lane_p"].fillna("").astype(str))]
    if m.empty:
        return pd.DataFrame(columns=cols)
    d = rectangle_point_distance(m["x_e"].to_numpy(), m["y_e"].to_numpy(), m["heading"].to_numpy(),
                                 m["length_e"].to_numpy(), m["width_e"].to_numpy(), m["x_p"].to_numpy(),
                                 m["y_p"].to_numpy())
    gap = d - person_radius(m["length_p"].to_numpy(), m["width_p"].to_numpy())
    return pd.DataFrame({"step": m["step"].to_numpy(), "time_s": m["time_s"].to_numpy(),
                         "ego": m["id_e"].astype(str).to_numpy(), "person": m["id_p"].astype(str).to_numpy(),
                         "gap_m": gap, "x": 0.5 * (m["x_e"].to_numpy() + m["x_p"].to_numpy()),
                         "y": 0.5 * (m["y_e"].to_numpy() + m["y_p"].to_numpy())})


def person_contact_events(traj: pd.DataFrame, pairs: pd.DataFrame) -> pd.DataFrame:
    """One event per (ego, person) pair and contact episode (consecutive recorded steps of ``traj``
    with contact); columns as the vehicles' events: step, time_s, a, b (ids, a < b), x, y."""
    hit = pairs[pairs["gap_m"] <= CONTACT_TOL_M]
    if hit.empty:
        return pd.DataFrame(columns=PERSON_EVENT_COLS)
    steps = np.unique(traj["step"].to_numpy()) if not traj.empty else np.unique(hit["step"].to_numpy())
    rank = np.searchsorted(steps, hit["step"].to_numpy())
    e, p = hit["ego"].to_numpy(str), hit["person"].to_numpy(str)
    c = pd.DataFrame({"step": hit["step"].to_numpy(), "time_s": hit["time_s"].to_numpy(),
                      "a": np.where(p < e, p, e), "b": np.where(p < e, e, p), "x": hit["x"].to_numpy(),
                      "y": hit["y"].to_numpy(), "_rank": rank}).sort_values(["a", "b", "_rank"], kind="stable")
    a, b, r = c["a"].to_numpy(), c["b"].to_numpy(), c["_rank"].to_numpy()
    cont = np.r_[False, (a[1:] == a[:-1]) & (b[1:] == b[:-1]) & (r[1:] == r[:-1] + 1)]
    return c.loc[~cont, PERSON_EVENT_COLS].sort_values(["step", "a", "b"], kind="stable").reset_index(drop=True)


def cyclist_gaps(traj: pd.DataFrame, classes: dict, apart=None) -> np.ndarray:
    """Gaps (m) between each ego's footprint and each VRU vehicle (cyclist, ...) at the same step."""
    if traj.empty or not classes:
        return np.zeros(0)
    vru = traj["id"].astype(str).map(lambda v: classes.get(v, "") in VRU_CLASSES).to_numpy(bool)
    is_ego = traj["is_ego"].to_numpy(bool)
    if not vru.any() or not is_ego.any():
        return np.zeros(0)
    lanes = bool(apart) and "lane" in traj
    cols = ["step", "x", "y", "heading", "length", "width"] + (["z"] if "z" in traj else []) + (["lane"] if lanes else [])
    m = traj.loc[is_ego, cols].merge(traj.loc[vru & ~is_ego, cols], on="step", suffixes=("_e", "_v"))
    if "z" in traj:  # pairs on one level only (core.levels)
        m = m[same_level(m["z_e"].to_numpy(float), m["z_v"].to_numpy(float))]
    if lanes:  # ... also by the net's topology (road.grade)
        m = m[~apart_pairs(apart, m["lane_e"].fillna("").astype(str), m["lane_v"].fillna("").astype(str))]
    if m.empty:
        return np.zeros(0)
    ce = footprint_corners(m[["x_e", "y_e"]].to_numpy(), m["heading_e"].to_numpy(), m["length_e"].to_numpy(),
                           m["width_e"].to_numpy())
    cv = footprint_corners(m[["x_v", "y_v"]].to_numpy(), m["heading_v"].to_numpy(), m["length_v"].to_numpy(),
                           m["width_v"].to_numpy())
    return convex_distance(ce, cv)[0]


def min_gap_vru_m(person_pairs: pd.DataFrame, cyclist_gap: np.ndarray) -> float | None:
    gaps = np.r_[np.maximum(person_pairs["gap_m"].to_numpy(float), 0.0), cyclist_gap]
    return float(gaps.min()) if gaps.size else None
