"""Seed 000's order parameters, partial fitnesses and μ (SPEC §1.1-1.2) of a flock's run. In an
arena φ_wall uses the vehicle centres against the square and the obstacles; on a road it is the
road footprint value (:func:`sumo_avoid.metrics.standard.phi_wall`)."""
from __future__ import annotations

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.metrics.order import flocking_metrics
from sumo_avoid.metrics.standard import ego_rows, phi_coll, phi_wall
from sumo_avoid.rollout.result import RunResult


class FlockingOrder(Metric):
    """v_vel, nearest-neighbour distance, clusters, disconnected, collisions, φ_wall, μ and its parts."""

    keys = Keys(("phi_corr", "v_vel", "n_disc", "n_min", "mean_nn_dist_m", "n_coll", "phi_coll", "phi_wall", "n_agents",
                 "mu_speed", "mu_coll", "mu_disc", "mu_cluster", "mu_wall", "mu_corr", "mu"))

    def compute(self, run: RunResult) -> dict:
        p = run.scenario.controller_params["flocking"]  # v_flock and r_c: [controllers.flocking], whoever drove
        return flocking_metrics(run.traj, v_flock=p.v_flock_mps, r_c_m=p.r_c_m, phi_coll=phi_coll(run),
                                phi_wall=phi_wall(run), egos=ego_rows(run))
