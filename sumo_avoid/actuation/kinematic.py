"""Turn each ego's desired 2-D velocity into motion within the vehicle's limits.

A kinematic car: speed changes within [-max_decel, +max_accel]; the heading turns towards the
desired direction at a yaw rate limited by ``max_yaw_rate``, by the lateral acceleration
(|v| * yaw_rate <= max_lat_accel) and by the turning radius (yaw_rate <= |v| / R_min), so a car
cannot turn on the spot. The commanded forward speed is the projection of the desired velocity on
the heading (a car slows down for a sharp turn and brakes when the desired velocity points
backwards). With ``max_reverse_speed_mps > 0`` a (nearly) stopped car whose desired direction is
more than 90 degrees off its heading reverses towards it instead (no dead zone between
forward and reverse in which a stopped car could do nothing).
Pure numpy, vectorised over egos; no SUMO here. Parameters: the ``[actuators.kinematic]`` table.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.actuation.held import HeldSpeed
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.geometry import wrap_angle
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import Motion, Observation

_REVERSE_ANGLE = np.radians(90.0)
#: A desired velocity slower than this (m/s) asks the car to stop; its direction, if any, is where to face
#: while it brakes (a car braking in a bend steers with the road instead of going on straight).
STOP_WISH_MPS = 1e-3
#: A car this slow (m/s) whose desired velocity lies more than 90 degrees off its heading reverses.
REVERSE_BELOW_MPS = 0.3


@dataclass(frozen=True)
class KinematicParams:
    max_accel_mps2: float = field_doc(3.0, doc="largest longitudinal acceleration, m/s^2")
    max_decel_mps2: float = field_doc(8.0, doc="largest braking deceleration, m/s^2")
    max_lat_accel_mps2: float = field_doc(4.0, doc="largest lateral acceleration v*yaw_rate, m/s^2")
    max_yaw_rate_radps: float = field_doc(0.8, doc="largest yaw rate, rad/s")
    min_turn_radius_m: float = field_doc(4.25, doc="smallest turning radius of the vehicle's centre (yaw rate <= v/R), m: "
                                                  "a compact car with an 11 m kerb-to-kerb turning circle (outer front "
                                                  "wheel on 5.5 m, 2.65 m wheelbase, 1.55 m track) turns its centre on 4.25 m")
    max_reverse_speed_mps: float = field_doc(2.0, doc="reverse gear speed limit, m/s (0 = no reversing)")


def actuate(pos, heading, speed, v_des, limits: KinematicParams, dt_s: float) -> Motion:
    """One step of the kinematic car for every ego.

    pos (E,2) m, heading (E,) rad, speed (E,) signed m/s, v_des (E,2) m/s desired velocity.
    """
    pos = np.asarray(pos, float).reshape(-1, 2)
    heading = np.asarray(heading, float).reshape(-1)
    speed = np.asarray(speed, float).reshape(-1)
    v_des = np.asarray(v_des, float).reshape(-1, 2)
    s_des = np.hypot(v_des[:, 0], v_des[:, 1])
    facing = s_des > 1e-9
    moving_wish = s_des >= STOP_WISH_MPS
    theta_des = np.where(facing, np.arctan2(v_des[:, 1], v_des[:, 0]), heading)
    err = wrap_angle(theta_des - heading)

    reverse = (limits.max_reverse_speed_mps > 0) & moving_wish & (np.abs(err) > _REVERSE_ANGLE) & (speed <= REVERSE_BELOW_MPS)
    err_used = np.where(reverse, wrap_angle(theta_des + np.pi - heading), err)
    target = np.where(
        reverse,
        -np.minimum(s_des * np.abs(np.cos(err)), limits.max_reverse_speed_mps),
        np.where(moving_wish, s_des * np.maximum(np.cos(err), 0.0), 0.0),
    )
    # growing |speed| (either gear) is limited by max_accel, shrinking it by max_decel
    speeding_up = (np.abs(target) > np.abs(speed)) & (target * speed >= 0)
    lim = np.where(speeding_up, limits.max_accel_mps2, limits.max_decel_mps2) * dt_s
    new_speed = speed + np.clip(target - speed, -lim, lim)
    # never jump from forward to reverse (or back) within one step: stop first
    new_speed = np.where((speed > 0) & (new_speed < 0), 0.0, new_speed)
    new_speed = np.where((speed < 0) & (new_speed > 0), 0.0, new_speed)

    v_abs = 0.5 * (np.abs(speed) + np.abs(new_speed))
    with np.errstate(divide="ignore", invalid="ignore"):
        yaw_lat = np.where(v_abs > 1e-9, limits.max_lat_accel_mps2 / v_abs, np.inf)
    yaw_max = np.minimum.reduce([np.full_like(v_abs, limits.max_yaw_rate_radps), yaw_lat,
                                 v_abs / max(limits.min_turn_radius_m, 1e-9)])
    dtheta = np.clip(err_used, -yaw_max * dt_s, yaw_max * dt_s)
    new_heading = wrap_angle(heading + dtheta)
    mid = heading + 0.5 * dtheta
    step = new_speed * dt_s
    new_pos = pos + np.column_stack([np.cos(mid), np.sin(mid)]) * step[:, None]
    return Motion(new_pos, new_heading, new_speed)


class KinematicActuator(HeldSpeed):
    """The kinematic car above (``ego.actuator = "kinematic"``, the default)."""

    def __init__(self, params: KinematicParams, ctx):
        super().__init__()
        self.p, self.dt = params, ctx.step_s

    @staticmethod
    def steering(params: KinematicParams) -> tuple[float, float]:
        """Controllers plan with the car's turning radius and yaw-rate limit."""
        return params.min_turn_radius_m, params.max_yaw_rate_radps

    def held(self, snap: Snapshot) -> Snapshot:
        return snap

    def step(self, obs: Observation, command: np.ndarray) -> Motion:
        snap, rows = obs.snapshot, obs.ego_rows
        motion = actuate(snap.pos[rows], snap.heading[rows], obs.ego_speed, command, self.p, self.dt)
        self._speed.update(zip(obs.ego_ids, motion.speed.tolist()))
        return motion
