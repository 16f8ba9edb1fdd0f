"""``policy``: a trained or scripted policy drives the egos, so that batches, suites and reports compare
it with the other controllers on the same scenarios.

Each step every ego's observation vector (:mod:`sumo_avoid.control.policy_obs`, the same vector the
Gymnasium environment :mod:`sumo_avoid.gym` hands an agent) goes to the policy, and its action becomes
the ego's desired velocity (the controller's command; the layers and the actuator follow as for any
controller):

* ``action = "velocity"`` (default): (v_s, v_d), the desired velocity along and across the ego's route,
  m/s, in [-max_reverse_speed_mps, max_speed_mps] x [-max_lateral_speed_mps, max_lateral_speed_mps]
  ((0, v) follows the lane at v);
* ``action = "accel_yaw"``: (acceleration, m/s^2; yaw rate, rad/s) within the kinematic actuator's
  limits (``[actuators.kinematic]``): the velocity of the held speed plus a dt along the heading turned
  by yaw rate x dt.

Actions outside those bounds are clipped. The policy is ``policy = "module:attribute"`` (importable
from the working directory or the installed packages): a callable ``f(observation) -> action`` on one
ego's float32 vector, an object with ``predict(observation, deterministic=True)`` (a Stable-Baselines3
model: the action is its first return), or a class instantiated with no arguments giving either.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from sumo_avoid.actuation.kinematic import KinematicParams
from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.control.policy_obs import PolicyObserver
from sumo_avoid.core.config import FieldError, field_doc
from sumo_avoid.core.registry import PluginNotFound, import_object, is_import_path
from sumo_avoid.core.types import EgoTask, Observation

ACTIONS = ("velocity", "accel_yaw")
POLICY_KEY = "controllers.policy.policy"


@dataclass(frozen=True)
class PolicyParams:
    policy: str = field_doc("", doc="import path 'module:attribute' of the policy (a callable observation -> "
                                    "action, a model with predict(), or a class making one); the Gymnasium "
                                    "environment gives its own")
    action: str = field_doc("velocity", doc="'velocity' (v_s, v_d along and across the route, m/s) or "
                                            "'accel_yaw' (acceleration m/s^2, yaw rate rad/s)")
    k_nearest: int = field_doc(8, doc="road users in the observation, nearest first")
    sense_radius_m: float = field_doc(80.0, positive=True, doc="road users farther than this are left out, m")
    route_points: int = field_doc(10, positive=True, doc="points of the route ahead in the observation")
    route_spacing_m: float = field_doc(5.0, positive=True, doc="spacing of those points along the route, m")
    max_speed_mps: float = field_doc(30.0, positive=True, doc="largest v_s of a velocity action, m/s")
    max_lateral_speed_mps: float = field_doc(3.0, doc="largest magnitude of v_d of a velocity action, m/s")

    def __post_init__(self):
        if self.action not in ACTIONS:
            raise FieldError("action", f"one of {list(ACTIONS)}", self.action)
        if self.policy and not is_import_path(self.policy):
            raise FieldError("policy", "an import path 'module:attribute' (e.g. 'mypkg.policies:keep_lane')",
                             self.policy)


def load_policy(path: str):
    """The callable ``observation -> action`` at import path ``path``. Raises :class:`FieldError` naming
    ``controllers.policy.policy`` when it is missing or does not import."""
    if not path:
        raise FieldError(POLICY_KEY, "the import path 'module:attribute' of the policy to run", show_got=False)
    if "" not in sys.path:  # the working directory, as `python -m` has it
        sys.path.insert(0, "")
    try:
        obj = import_object(path)
    except PluginNotFound as e:
        raise FieldError(POLICY_KEY, f"an importable policy ({e})", path) from None
    if isinstance(obj, type):
        obj = obj()
    predict = getattr(obj, "predict", None)
    if predict is not None:
        return lambda x: predict(x, deterministic=True)[0]
    if not callable(obj):
        raise FieldError(POLICY_KEY, "a callable observation -> action, or an object with predict()", path)
    return obj


def kinematic_limits(tables) -> KinematicParams:
    """The kinematic actuator's limits in a scenario's tables by name (``[actuators.kinematic]``;
    ``Context.params``, ``Scenario.tables``), its defaults when they have none."""
    return tables.get("actuators.kinematic") or KinematicParams()


def action_bounds(params: PolicyParams, limits: KinematicParams) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) float32 of an action (:data:`ACTIONS`: ``params.action``)."""
    if params.action == "accel_yaw":
        lo, hi = [-limits.max_decel_mps2, -limits.max_yaw_rate_radps], [limits.max_accel_mps2, limits.max_yaw_rate_radps]
    else:
        lo = [-limits.max_reverse_speed_mps, -params.max_lateral_speed_mps]
        hi = [params.max_speed_mps, params.max_lateral_speed_mps]
    return np.array(lo, np.float32), np.array(hi, np.float32)


class PolicyController(BaseController):
    """A policy (trained or scripted) on the observation vector of sumo_avoid.gym."""

    def __init__(self, params: PolicyParams, ctx=None, policy=None):
        super().__init__(params, ctx)
        self.observer = PolicyObserver(params, ctx)
        self.policy = policy if policy is not None else load_policy(params.policy)
        self.limits = kinematic_limits(ctx.params if ctx is not None else {})
        self.low, self.high = action_bounds(params, self.limits)
        self.step_s = ctx.step_s if ctx is not None else 0.1
        self._seen: tuple = (None, None)  # (observation, its vectors): one computation per step

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        self.observer.add_ego(task)

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        self.observer.remove_ego(vid)

    def observe(self, obs: Observation) -> np.ndarray:
        """(E, D) observation vectors of this step, computed once per step (the route frames track the
        egos' arc lengths from step to step)."""
        if self._seen[0] is not obs:
            self._seen = (obs, self.observer(obs))
        return self._seen[1]

    def decide(self, ego_ids: tuple[str, ...], x: np.ndarray) -> np.ndarray:
        """(E, 2) actions of the egos for their observations ``x`` (E, D)."""
        return np.array([np.asarray(self.policy(row), float).reshape(2) for row in x]).reshape(-1, 2)

    def act(self, obs: Observation) -> np.ndarray:
        return self.command(obs, self.decide(obs.ego_ids, self.observe(obs)))

    def command(self, obs: Observation, actions: np.ndarray) -> np.ndarray:
        """(E, 2) desired velocities, m/s, of the actions (E, 2) (clipped to their bounds)."""
        a = np.clip(np.asarray(actions, float).reshape(-1, 2), self.low, self.high)
        out = np.zeros((len(obs.ego_ids), 2))
        if self.p.action == "accel_yaw":
            rows = obs.ego_rows
            speed = np.maximum(obs.ego_speed + a[:, 0] * self.step_s, 0.0)
            heading = obs.snapshot.heading[rows] + a[:, 1] * self.step_s
            return speed[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
        for k, vid in enumerate(obs.ego_ids):
            sc = self.observer.scenes[vid]
            out[k] = self.observer.views[vid].to_xy_velocity(sc.s, sc.d, a[k], self.step_s)
        return out
