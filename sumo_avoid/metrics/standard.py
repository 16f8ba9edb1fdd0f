"""The metrics every run gets (README "Metrics"): what ran, collisions (ours and SUMO's), the
smallest gap, SPEC §1.1's phi_coll and phi_wall, the plug-ins' counters and the egos' motion."""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid import __version__
from sumo_avoid.core.geometry import footprint_corners
from sumo_avoid.core.types import Keys
from sumo_avoid.metrics import basic, contacts, vru
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.ego_rows import EgoRows
from sumo_avoid.metrics.pairs import Rows
from sumo_avoid.road.walls import outside_distance as arena_outside_distance
from sumo_avoid.rollout.result import RunResult

RULES_LAYER = "traffic"  # the rules of the road: metrics.json's "safety" names the layers besides it


def ego_outside_distance(run: RunResult) -> np.ndarray:
    """Per ego-step, how far the ego's footprint sticks out of the road's drivable area for its vehicle
    class (the lanes open to it and the junctions: a car on the sidewalk is out), m."""
    ego = run.traj[run.traj["is_ego"]]
    if ego.empty:
        return np.zeros(0)
    corners = footprint_corners(ego[["x", "y"]].to_numpy(), ego["heading"].to_numpy(),
                                ego["length"].to_numpy(), ego["width"].to_numpy())
    ids = ego["id"].astype(str).to_numpy()
    classes = {v: ego_class(run, v) for v in np.unique(ids)}
    if len(set(classes.values())) <= 1:  # one class (the usual case): one query
        return run.road.footprint_outside_distance(corners, next(iter(classes.values()), None))
    out = np.zeros(len(ego))
    for v, vc in classes.items():
        rows = ids == v
        out[rows] = run.road.footprint_outside_distance(corners[rows], vc)
    return out


def ego_class(run: RunResult, vid: str) -> str | None:
    """An ego's SUMO vehicle class (its drivable area: the lanes open to it), None when not known."""
    task = run.tasks.get(vid)
    return run.classes.get(vid) or (task.vclass if task is not None else None)


def pair_rows(run: RunResult) -> Rows:
    """The table's columns and k-d tree pair search shared by collisions, min_gap and phi_coll."""
    return run.memo("pair_rows", lambda: Rows.of(run.traj, road_apart(run)))


def road_apart(run: RunResult) -> dict:
    """Edges crossing without a junction on the run's net (road.grade; none in an arena, as in the run's snapshots)."""
    return {} if run.scene.walls is not None else getattr(run.road, "apart", {})


def ego_rows(run: RunResult) -> EgoRows:
    """The ego rows and id codes shared by motion, comfort, road use and the order parameters."""
    return run.memo("ego_rows", lambda: EgoRows.of(run.traj))


def phi_coll(run: RunResult) -> float:
    return run.memo("phi_coll", lambda: basic.phi_coll(run.traj, run.scenario.spec.sim.step_s, rows=pair_rows(run)))


def phi_wall(run: RunResult) -> float:
    """SPEC §1.1 φ_wall against the run's allowed area: the road's drivable area (ego footprints), or
    in an arena its walls and obstacles (ego centres, as the flocking seed defines it)."""
    return run.memo("phi_wall", lambda: basic.phi_wall(outside_distance(run)))


def outside_distance(run: RunResult) -> np.ndarray:
    scene = run.scene
    if scene.walls is None:
        return ego_outside_distance(run)
    ego = run.traj[run.traj["is_ego"]]
    return arena_outside_distance(ego[["x", "y"]].to_numpy(), scene.walls, scene.obstacles)


class RunInfo(Metric):
    """What ran: scenario, controller, sensor, the chosen layers besides the rules of the road
    (``safety``: e.g. "danger_time", several joined by "+", "none" if only "traffic" or no layer),
    seed, step, simulated time, version."""

    keys = Keys(("seed", "step_s", "sim_time_s", "steps"),
                text=("scenario", "controller", "sensor", "safety", "sumo_avoid_version"))

    def compute(self, run: RunResult) -> dict:
        spec = run.scenario.spec
        return {"scenario": spec.name, "controller": spec.ego.controller, "sensor": spec.ego.sensor,
                "safety": "+".join(n for n in spec.ego.layers if n != RULES_LAYER) or "none", "seed": spec.sim.seed, "step_s": spec.sim.step_s,
                "sim_time_s": run.sim_time_s, "steps": run.steps, "sumo_avoid_version": __version__}


class Collisions(Metric):
    """Footprint contact events found by the plug-in, SUMO's own reports, and where they disagree."""

    keys = Keys(("collisions", "collisions_ego_stopped", "collisions_other_jumped", "max_impact_speed_mps",
                 "sumo_collisions", "sumo_ego_collisions"),
                nested=("collision_events", "sumo_collision_events", "collision_pairs_only_ours",
                        "collision_pairs_only_sumo", "collision_disagreements"))

    def compute(self, run: RunResult) -> dict:
        events = all_collision_events(run)
        sumo = run.sumo_events
        egos = set(run.traj.loc[run.traj["is_ego"].astype(bool), "id"].astype(str)) if len(run.traj) else set()
        ours = {tuple(sorted(p)) for p in zip(events["a"], events["b"])}
        theirs = {tuple(sorted(p)) for p in zip(sumo["a"], sumo["b"])}
        return {"collisions": len(events), "collision_events": events.to_dict(orient="records"),
                **contact_counts(events),
                "sumo_collisions": len(sumo), "sumo_collision_events": sumo.to_dict(orient="records"),
                "sumo_ego_collisions": sum(a in egos or b in egos for a, b in zip(sumo["a"], sumo["b"])),
                "collision_pairs_only_ours": sorted(map(list, ours - theirs)),
                "collision_pairs_only_sumo": sorted(map(list, theirs - ours)),
                "collision_disagreements": disagreements(recorded(run), events, sumo, ours - theirs, theirs - ours)}


def contact_counts(events: pd.DataFrame, prefix: str = "collisions", mask=None) -> dict:
    """How the contacts happened, counted (metrics.contacts): with the ego standing, with the other party arriving
    by a jump, and the largest impact speed (None without a contact); ``prefix`` "vru_collisions" for the
    ``mask``ed ones with a vulnerable road user."""
    ev = events if mask is None else events[mask]
    if "kind" not in ev:
        ev = ev.assign(kind=pd.Series(dtype=object), other_jumped=pd.Series(dtype=bool),
                       impact_speed_mps=pd.Series(dtype=float))
    impact = ev["impact_speed_mps"].astype(float)
    return {f"{prefix}_ego_stopped": int((ev["kind"] == "ego_stopped").sum()),
            f"{prefix}_other_jumped": int(ev["other_jumped"].astype(bool).sum()),
            "max_impact_speed_vru_mps" if prefix.startswith("vru") else "max_impact_speed_mps":
            float(impact.max()) if len(impact) else None}


def person_pairs(run: RunResult):
    """Every (ego, person) pair at one recorded step with its gap (metrics.vru), computed once per run."""
    return run.memo("person_pairs", lambda: vru.ego_person_pairs(run.traj, run.persons, road_apart(run)))


def all_collision_events(run: RunResult):
    """The plug-in's contact events: vehicles (footprints) and persons (discs), by step, with the class of
    the party that is not the ego (or of the second ego) in ``other_class``."""
    def compute():
        cars = basic.collision_events(run.traj, rows=pair_rows(run))
        people = vru.person_contact_events(run.traj, person_pairs(run))
        if people.empty:
            ev = cars.assign(_person=False)
        elif cars.empty:
            ev = people.assign(_person=True)
        else:
            ev = pd.concat([cars.assign(_person=False), people.assign(_person=True)], ignore_index=True)
        ev = ev.sort_values(["step", "a", "b"], kind="stable").reset_index(drop=True)
        with_person = ev.pop("_person").to_numpy(bool)
        egos = set(run.traj.loc[run.traj["is_ego"].astype(bool), "id"].astype(str)) if len(run.traj) else set()
        ev = contacts.describe(ev, run.traj, run.persons, egos, with_person)  # how each happened, and who the ego is
        if run.classes:  # a run recorded with classes (every run since persons are recorded)
            other = np.where(ev["ego"].astype(str) == ev["a"].astype(str), ev["b"].astype(str), ev["a"].astype(str))
            ev = ev.assign(other_class=[run.classes.get(o, "") for o in other])
        return ev
    return run.memo("collision_events", compute)


def recorded(run: RunResult):
    """The vehicles' and persons' rows together (for looking up where SUMO had a party)."""
    if run.persons is None or run.persons.empty:
        return run.traj
    return pd.concat([run.traj, run.persons], ignore_index=True)


def _lanes_at(traj, step, ids) -> list[str]:
    if "lane" not in traj:
        return ["" for _ in ids]
    now = traj[traj["step"] == step]
    lane = dict(zip(now["id"].astype(str), now["lane"].fillna("").astype(str)))
    return [lane.get(v, "") for v in ids]


def _unrecorded(traj, step, ids) -> list[str]:
    """The ids of ``ids`` not in the recording at ``step`` or the step before (SUMO reports a collision
    after the step it happened in)."""
    if "step" not in traj or traj.empty:
        return list(ids)
    near = set(traj.loc[traj["step"].isin((step, step - 1)), "id"].astype(str))
    return [v for v in ids if v not in near]


def why_only_ours(la: str, lb: str, a: str, b: str) -> str:
    """Why SUMO's lane-based check would miss a contact our footprints found, from the lanes SUMO
    had the two vehicles on (SUMO checks vehicles on one lane, or on conflicting links in a junction)."""
    if not la or not lb:
        return f"'{a if not la else b}' is on no lane in SUMO's view (off the network)"
    if la.startswith(":") and lb.startswith(":"):
        return (f"both inside junction {la[1:].rsplit('_', 2)[0]} ({la}, {lb}): SUMO checks a junction only "
                f"between links it knows to conflict, never on an unregulated one")
    if la.rsplit("_", 1)[0] != lb.rsplit("_", 1)[0]:
        return f"on different edges in SUMO's view ({la}, {lb}): SUMO checks vehicles on the same lane"
    if la != lb:
        return f"on neighbouring lanes in SUMO's view ({la}, {lb}): a lateral contact across a lane border"
    return f"on the same lane in SUMO's view ({la}): SUMO measures the gap along the lane, we the footprints"


def disagreements(traj, events, sumo, only_ours, only_sumo) -> list[dict]:
    """One line per pair only one of the two collision checks found, and why. A pair SUMO reports
    with a party the recording does not have at that time is said to be unseen by the plug-in, never
    explained away."""
    out = []
    for pair in sorted(only_ours):
        ev = events[(events["a"] == pair[0]) & (events["b"] == pair[1])].iloc[0]
        la, lb = _lanes_at(traj, ev["step"], pair)
        out.append({"pair": list(pair), "found_by": "plug-in", "time_s": float(ev["time_s"]),
                    "why": why_only_ours(la, lb, *pair)})
    for pair in sorted(only_sumo):
        ev = sumo[(sumo["a"] == pair[0]) & (sumo["b"] == pair[1])].iloc[0]
        missing = _unrecorded(traj, ev["step"], pair)
        if missing:
            out.append({"pair": list(pair), "found_by": "SUMO", "time_s": float(ev["time_s"]),
                        "why": f"SUMO reported a {ev['type']} on {ev['lane']}; the plug-in has no record of "
                               f"{', '.join(repr(m) for m in missing)} at that time: it cannot judge it"})
            continue
        out.append({"pair": list(pair), "found_by": "SUMO", "time_s": float(ev["time_s"]),
                    "why": f"SUMO reported a {ev['type']} on {ev['lane']} from its lane geometry; the "
                           f"footprints (exact poses) did not overlap"})
    return out


class VulnerableRoadUsers(Metric):
    """SPEC §6: the egos' contacts with persons and cyclists (``vru_collisions``, also in ``collisions``)
    and the smallest gap to one (:mod:`sumo_avoid.metrics.vru`)."""

    keys = Keys(("vru_collisions", "vru_collisions_ego_stopped", "vru_collisions_other_jumped",
                 "max_impact_speed_vru_mps", "min_gap_vru_m"))

    def compute(self, run: RunResult) -> dict:
        ev = all_collision_events(run)
        is_vru = ev["other_class"].isin(vru.VRU_CLASSES) if "other_class" in ev else pd.Series(False, index=ev.index)
        gap = vru.min_gap_vru_m(person_pairs(run), vru.cyclist_gaps(run.traj, run.classes, road_apart(run)))
        return {"vru_collisions": int(is_vru.sum()), **contact_counts(ev, "vru_collisions", is_vru),
                "min_gap_vru_m": gap}


class MinGap(Metric):
    """Smallest footprint-to-footprint distance between an ego and any other vehicle, m."""

    keys = Keys(("min_gap_m",))

    def compute(self, run: RunResult) -> dict:
        return {"min_gap_m": basic.min_gap_m(run.traj, rows=pair_rows(run))}


class PhiColl(Metric):
    """SPEC §1.1 collision risk (centre distance < 3 m), averaged over time."""

    keys = Keys(("phi_coll",))

    def compute(self, run: RunResult) -> dict:
        return {"phi_coll": phi_coll(run)}


class PhiWall(Metric):
    """SPEC §1.1: mean distance the egos stick out of the allowed area (road or arena), m."""

    keys = Keys(("phi_wall",))

    def compute(self, run: RunResult) -> dict:
        return {"phi_wall": phi_wall(run)}


class PluginStats(Metric):
    """The plug-ins' own counters (SA escapes, danger-time interventions, flocking updates)."""

    keys = Keys()  # those of the run's plug-ins:

    @classmethod
    def keys_for(cls, scn, stats: Keys) -> Keys:
        return stats

    def compute(self, run: RunResult) -> dict:
        return dict(run.stats)


class Motion(Metric):
    """Goal reached, time to goal, path length, mean speed, per ego; how many egos drove round a U-turn of their
    route (``route_detours``, rollout.egos: their routes differ from SUMO's driver's on the same scenario)."""

    keys = Keys(("goal_reached", "time_to_goal_s", "path_length_m", "mean_speed_mps", "route_detours"), nested=("per_ego",))

    def compute(self, run: RunResult) -> dict:
        return {**basic.motion_summary(run.traj, run.goals, run.scenario.spec.ego.goal_tolerance_m, ego_rows(run),
                                       arrivals=run.arrivals), "route_detours": len(run.detours)}
