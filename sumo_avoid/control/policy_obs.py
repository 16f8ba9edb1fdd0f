"""The fixed-size observation a policy sees (:class:`~sumo_avoid.control.policy.PolicyController`, the
Gymnasium environment :mod:`sumo_avoid.gym`): one float32 vector per ego, built from the run's sensor
in the ego's route frame (:class:`~sumo_avoid.control.road_view.RoadView`: s along the route's
reference path, d across it, left > 0).

Layout (docs/gym.md has the table), in this order:

* ego (5): signed speed the actuator holds, m/s; d, m; heading relative to the route, rad;
  velocity along and across the route (s_dot, d_dot), m/s;
* goal (2): the goal's s and d minus the ego's, m;
* route ahead (4 x ``route_points``): at s + k ``route_spacing_m`` (k = 1..M) the route's point in the
  ego's body frame (x forward, y left), m, and the bounds of the ego's lanes there (d_lo, d_hi) minus
  the ego's d, m;
* others (7 x ``k_nearest``): the K road users nearest in (s, d) among those the sensor gives within
  ``sense_radius_m`` (ground truth, or the radar's detections and tracker memory), nearest first:
  present (1/0), ds, dd, m; their velocity minus the ego's (s_dot, d_dot), m/s; length, width, m.
  Empty slots are all zeros.

Every value is clipped to :func:`bounds` (the environment's observation space). Pure numpy apart
from the route frame; no SUMO here.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.control.road_view import MAX_ABS_D_M, FrenetScene, RoadView
from sumo_avoid.core.types import EgoTask, Observation

EGO = ("speed_mps", "d_m", "heading_rad", "v_s_mps", "v_d_mps")
GOAL = ("goal_ds_m", "goal_dd_m")
ROUTE = ("x_m", "y_m", "d_lo_m", "d_hi_m")  # per point ahead
OTHER = ("present", "ds_m", "dd_m", "dv_s_mps", "dv_d_mps", "length_m", "width_m")  # per slot
#: Largest speed and relative speed an observation holds, m/s; largest goal distance, m.
SPEED_BOUND_MPS = 60.0
GOAL_BOUND_M = 100_000.0
#: Largest length and width of a road user, m.
SIZE_BOUND_M = 30.0


def size(p) -> int:
    """Length of the observation vector for parameters ``p`` (:class:`~sumo_avoid.control.policy.PolicyParams`)."""
    return len(EGO) + len(GOAL) + len(ROUTE) * p.route_points + len(OTHER) * p.k_nearest


def names(p) -> list[str]:
    """The name of every entry of the vector, in order ("route3.x_m", "other0.ds_m", ...)."""
    return ([*EGO, *GOAL] + [f"route{k}.{n}" for k in range(p.route_points) for n in ROUTE]
            + [f"other{k}.{n}" for k in range(p.k_nearest) for n in OTHER])


def bounds(p) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) float32 vectors of :func:`size`: what each entry may hold."""
    reach = p.route_points * p.route_spacing_m + 10.0
    lane = 2.0 * MAX_ABS_D_M + 10.0
    hi = ([SPEED_BOUND_MPS, lane, np.pi, SPEED_BOUND_MPS, SPEED_BOUND_MPS, GOAL_BOUND_M, GOAL_BOUND_M]
          + [reach, reach, lane, lane] * p.route_points
          + [1.0, p.sense_radius_m, p.sense_radius_m, 2 * SPEED_BOUND_MPS, 2 * SPEED_BOUND_MPS, SIZE_BOUND_M,
             SIZE_BOUND_M] * p.k_nearest)
    hi = np.array(hi, np.float32)
    lo = -hi
    other = len(EGO) + len(GOAL) + len(ROUTE) * p.route_points
    for k in range(p.k_nearest):  # present, length and width are never negative
        j = other + k * len(OTHER)
        lo[[j, j + 5, j + 6]] = 0.0
    return lo, hi


class PolicyObserver:
    """Each ego's route frame (from ``add_ego`` to ``remove_ego``) and the observation vectors of a
    step; ``scenes`` keeps this step's :class:`FrenetScene` by ego (the action and the reward read it)."""

    def __init__(self, params, ctx):
        self.p = params
        self.turn_radius_m = ctx.turn_radius_m if ctx is not None else 0.0
        self.yaw_rate_radps = ctx.yaw_rate_radps if ctx is not None else np.inf
        self.views: dict[str, RoadView] = {}
        self.scenes: dict[str, FrenetScene] = {}
        self.low, self.high = bounds(params)

    def add_ego(self, task: EgoTask) -> None:
        self.views[task.vid] = RoadView(task, self.turn_radius_m, self.yaw_rate_radps)

    def remove_ego(self, vid: str) -> None:
        self.views.pop(vid, None)
        self.scenes.pop(vid, None)

    def __call__(self, obs: Observation) -> np.ndarray:
        """(E, size) float32, rows in the order of ``obs.ego_ids``."""
        out = np.zeros((len(obs.ego_ids), size(self.p)), np.float32)
        for k, (vid, row) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            view = self.views[vid]
            sc = view.scene(obs, int(row), self.p.sense_radius_m)
            self.scenes[vid] = sc
            out[k] = np.clip(self._vector(view, sc, obs, k, int(row)), self.low, self.high)
        return out

    def _vector(self, view: RoadView, sc: FrenetScene, obs: Observation, k: int, row: int) -> np.ndarray:
        p = self.p
        snap = obs.snapshot
        ego = [float(obs.ego_speed[k]), sc.d, sc.heading, float(sc.vel[0]), float(sc.vel[1])]
        goal = [float(view.goal[0]) - sc.s, float(view.goal[1]) - sc.d]
        s_ahead = np.minimum(sc.s + p.route_spacing_m * np.arange(1, p.route_points + 1), view.length_m)
        h = float(snap.heading[row])
        rel = view.frame.to_xy(s_ahead, view.line.offset(s_ahead)) - snap.pos[row]
        c, sn = np.cos(h), np.sin(h)
        body = np.column_stack([c * rel[:, 0] + sn * rel[:, 1], -sn * rel[:, 0] + c * rel[:, 1]])
        lo, hi = view.corridor(s_ahead)
        lane = 2.0 * MAX_ABS_D_M
        route = np.column_stack([body, np.clip(lo, -lane, lane) - sc.d, np.clip(hi, -lane, lane) - sc.d])
        others = np.zeros((p.k_nearest, len(OTHER)))
        if len(sc.o_pos):
            dq = sc.o_pos - sc.q
            near = np.argsort(np.hypot(dq[:, 0], dq[:, 1]), kind="stable")[:p.k_nearest]
            n = len(near)
            others[:n, 0] = 1.0
            others[:n, 1:3] = dq[near]
            others[:n, 3:5] = sc.o_vel[near] - sc.vel
            others[:n, 5] = sc.o_length[near]
            others[:n, 6] = sc.o_width[near]
        return np.concatenate([ego, goal, route.ravel(), others.ravel()])
