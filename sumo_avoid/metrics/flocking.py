"""Seed 000's order parameters, partial fitnesses and μ (SPEC §1.1-1.2) of a flock's run. In an
arena φ_wall uses the vehicle centres against the square and the obstacles; on a road it is the
road footprint value."""
from __future__ import annotations

from sumo_avoid.metrics import basic
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.order import flocking_metrics
from sumo_avoid.metrics.standard import phi_coll, road_phi_wall
from sumo_avoid.rollout.arena import outside_distance
from sumo_avoid.rollout.result import RunResult


def flock_phi_wall(run: RunResult) -> float:
    scene = run.scene
    if scene.walls is None:
        return road_phi_wall(run)
    ego = run.traj[run.traj["is_ego"]]
    return basic.phi_wall(outside_distance(ego[["x", "y"]].to_numpy(), scene.walls, scene.obstacles))


class FlockingOrder(Metric):
    """v_vel, nearest-neighbour distance, clusters, disconnected, collisions, φ_wall, μ and its parts."""

    def compute(self, run: RunResult) -> dict:
        p = run.scenario.params
        return flocking_metrics(run.traj, v_flock=p.v_flock_mps, r_c_m=p.r_c_m, phi_coll=phi_coll(run),
                                phi_wall=flock_phi_wall(run))
