"""The metrics every run gets (README "Metrics"): what ran, collisions (ours and SUMO's), the
smallest gap, SPEC §1.1's phi_coll and phi_wall, the plug-ins' counters and the egos' motion."""
from __future__ import annotations

import numpy as np

from sumo_avoid import __version__
from sumo_avoid.core.geometry import footprint_corners
from sumo_avoid.metrics import basic
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.pairs import Rows
from sumo_avoid.rollout.arena import outside_distance as arena_outside_distance
from sumo_avoid.rollout.result import RunResult


def ego_outside_distance(run: RunResult) -> np.ndarray:
    """Per ego-step, how far the ego's footprint sticks out of the road's drivable area, m."""
    ego = run.traj[run.traj["is_ego"]]
    if ego.empty:
        return np.zeros(0)
    corners = footprint_corners(ego[["x", "y"]].to_numpy(), ego["heading"].to_numpy(),
                                ego["length"].to_numpy(), ego["width"].to_numpy())
    return run.road.footprint_outside_distance(corners)


def pair_rows(run: RunResult) -> Rows:
    """The table's columns and k-d tree pair search shared by collisions, min_gap and phi_coll."""
    return run.memo("pair_rows", lambda: Rows.of(run.traj))


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
    """What ran: scenario, controller, sensor, layer, seed, step, simulated time, version."""

    def compute(self, run: RunResult) -> dict:
        spec = run.scenario.spec
        return {"scenario": spec.name, "controller": spec.ego.controller, "sensor": spec.ego.sensor,
                "safety": spec.ego.safety, "seed": spec.sim.seed, "step_s": spec.sim.step_s,
                "sim_time_s": run.sim_time_s, "steps": run.steps, "sumo_avoid_version": __version__}


class Collisions(Metric):
    """Footprint contact events found by the plug-in, SUMO's own reports, and where they disagree."""

    def compute(self, run: RunResult) -> dict:
        events = run.memo("collision_events", lambda: basic.collision_events(run.traj, rows=pair_rows(run)))
        sumo = run.sumo_events
        ours = {tuple(sorted(p)) for p in zip(events["a"], events["b"])}
        theirs = {tuple(sorted(p)) for p in zip(sumo["a"], sumo["b"])}
        return {"collisions": int(len(events)), "collision_events": events.to_dict(orient="records"),
                "sumo_collisions": int(len(sumo)), "sumo_collision_events": sumo.to_dict(orient="records"),
                "collision_pairs_only_ours": sorted(map(list, ours - theirs)),
                "collision_pairs_only_sumo": sorted(map(list, theirs - ours))}


class MinGap(Metric):
    """Smallest footprint-to-footprint distance between an ego and any other vehicle, m."""

    def compute(self, run: RunResult) -> dict:
        return {"min_gap_m": basic.min_gap_m(run.traj, rows=pair_rows(run))}


class PhiColl(Metric):
    """SPEC §1.1 collision risk (centre distance < 3 m), averaged over time."""

    def compute(self, run: RunResult) -> dict:
        return {"phi_coll": phi_coll(run)}


class PhiWall(Metric):
    """SPEC §1.1: mean distance the egos stick out of the allowed area (road or arena), m."""

    def compute(self, run: RunResult) -> dict:
        return {"phi_wall": phi_wall(run)}


class PluginStats(Metric):
    """The plug-ins' own counters (SA escapes, danger-time interventions, flocking updates)."""

    def compute(self, run: RunResult) -> dict:
        return dict(run.stats)


class Motion(Metric):
    """Goal reached, time to goal, path length, mean speed, per ego."""

    def compute(self, run: RunResult) -> dict:
        return basic.motion_summary(run.traj, run.goals, run.scenario.spec.ego.goal_tolerance_m)
