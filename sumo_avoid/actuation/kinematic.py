"""Turn each ego's desired 2-D velocity into motion within the vehicle's limits.

A kinematic car: speed changes within [-max_decel, +max_accel]; the heading turns towards the
desired direction at a yaw rate limited by ``max_yaw_rate``, by the lateral acceleration
(|v| * yaw_rate <= max_lat_accel) and by the turning radius, so a car cannot turn on the spot. By default
it turns about its centre (``rear_axle_m`` 0), which swings the rear of a 4.5 m car out by 2.25 m x the heading
change: unseen Cologne, an ego creeping at 1.3 m/s that turned 0.17 rad away from a person ahead swung its rear
0.4 m into a cyclist passing it on the right. With ``rear_axle_m`` b > 0 it turns about a rear axle b behind its
centre (a bicycle model): the axle moves along the heading, the centre turns with the car, the centre's radius
R_min allows yaw_rate <= |v| / sqrt(R_min^2 - b^2), and the rear swings out by (L/2 - b) x the heading change.
Experimental: with b = 1.325 m Cologne's contacts went 1 -> 0 (truth) and 3 -> 1 (radar, seed 1), but the road
controllers' turns are fitted to the centre: six behaviour tests failed (a turn tighter than the car and a
turnaround cut the kerb, phi_wall 0.28 / 0.32 m; two radar overtakings missed their goal; the ego waiting for a
narrow street and letting a faster car pass before a lane change came closer than they allow).
The commanded forward speed is the projection of the desired velocity on the heading (a car slows down
for a sharp turn and brakes when the desired velocity points backwards). With ``max_reverse_speed_mps > 0``
a (nearly) stopped car whose desired direction is more than 90 degrees off its heading reverses towards it
instead (no dead zone between forward and reverse in which a stopped car could do nothing).
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
    min_turn_radius_m: float = field_doc(4.25, doc="smallest turning radius of the vehicle's centre, m: "
                                                  "a compact car with an 11 m kerb-to-kerb turning circle (outer front "
                                                  "wheel on 5.5 m, 2.65 m wheelbase, 1.55 m track) turns its centre on 4.25 m")
    max_reverse_speed_mps: float = field_doc(2.0, doc="reverse gear speed limit, m/s (0 = no reversing)")
    rear_axle_m: float = field_doc(0.0, doc="how far behind the vehicle's centre it turns, m: 0 = about the centre (the "
                                           "road controllers are built for it); 1.325 = about the rear axle of "
                                           "min_turn_radius_m's compact car (2.65 m wheelbase), whose rear does not "
                                           "swing out (experimental: module doc)")

    def __post_init__(self):
        if self.rear_axle_m > 0.0 and self.rear_axle_m >= self.min_turn_radius_m:
            raise ValueError("actuators.kinematic.rear_axle_m < min_turn_radius_m (the centre turns on a circle round it)")


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
    b = limits.rear_axle_m
    # the radius the turning point may take: R_min, or the axle's radius that puts the centre on R_min
    r_turn = np.sqrt(max(limits.min_turn_radius_m ** 2 - b * b, 1e-18))
    yaw_max = np.minimum.reduce([np.full_like(v_abs, limits.max_yaw_rate_radps), yaw_lat, v_abs / r_turn])
    dtheta = np.clip(err_used, -yaw_max * dt_s, yaw_max * dt_s)
    new_heading = wrap_angle(heading + dtheta)
    mid = heading + 0.5 * dtheta
    step = new_speed * dt_s
    new_pos = pos + np.column_stack([np.cos(mid), np.sin(mid)]) * step[:, None]
    if b > 0.0:  # the rear axle moves along the heading; the centre, b ahead of it, turns with the car
        turn = np.column_stack([np.cos(new_heading) - np.cos(heading), np.sin(new_heading) - np.sin(heading)])
        new_pos = new_pos + b * turn
    return Motion(new_pos, new_heading, new_speed)


class KinematicActuator(HeldSpeed):
    """The kinematic car above (``ego.actuator = "kinematic"``, the default)."""

    def __init__(self, params: KinematicParams, ctx):
        super().__init__()
        self.p, self.dt = params, ctx.step_s

    @staticmethod
    def steering(params: KinematicParams) -> tuple[float, float, float]:
        """Controllers plan with the car's turning radius, yaw-rate limit and where it turns about."""
        return params.min_turn_radius_m, params.max_yaw_rate_radps, params.rear_axle_m

    def held(self, snap: Snapshot) -> Snapshot:
        return snap

    def step(self, obs: Observation, command: np.ndarray) -> Motion:
        snap, rows = obs.snapshot, obs.ego_rows
        motion = actuate(snap.pos[rows], snap.heading[rows], obs.ego_speed, command, self.p, self.dt)
        self._speed.update(zip(obs.ego_ids, motion.speed.tolist()))
        return motion
