"""The reference simulator's vehicle response (SPEC §1.3, flocking): velocity relaxation
dv/dt = (v_des - v)/τ with |dv/dt| <= a_max, heading along the velocity, optional outer noise.

The actuator holds each ego's velocity itself (SUMO's reported speed of an off-lane vehicle is
unreliable) and hands it back through :meth:`RelaxationActuator.held`. Parameters: the
``[actuators.relaxation]`` table.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sumo_avoid.actuation.held import HeldSpeed
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.noise import velocity_kick
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import Motion, Observation


@dataclass(frozen=True)
class RelaxationParams:
    tau_s: float = field_doc(1.0, positive=True, doc="velocity time constant tau, s")
    max_accel_mps2: float = field_doc(6.0, doc="acceleration cap: the norm of dv/dt at most this, m/s^2")
    outer_noise_m2ps3: float = field_doc(0.0, doc="reference simulator's 'outer' noise on the actual motion, sigma "
                                                  "in m^2/s^3 (robotsim: 0.2; 0 = off; sumo_avoid/core/noise.py)")


def relax(vel, v_des, tau_s: float, max_accel_mps2: float, dt_s: float):
    """Reference-simulator vehicle response: dv/dt = (v_des - v)/τ with |dv/dt| <= a_max.

    vel, v_des (E,2) m/s. Returns (new velocity (E,2), acceleration used (E,2)); the caller moves
    the vehicle by new_velocity·dt (semi-implicit Euler).
    """
    vel = np.asarray(vel, float).reshape(-1, 2)
    acc = (np.asarray(v_des, float).reshape(-1, 2) - vel) / tau_s
    a = np.hypot(acc[:, 0], acc[:, 1])
    scale = np.where(a > max_accel_mps2, max_accel_mps2 / np.maximum(a, 1e-12), 1.0)
    acc = acc * scale[:, None]
    return vel + acc * dt_s, acc


def relaxation_step(pos, vel, heading, v_des, tau_s, max_accel_mps2, dt_s, kick=None):
    """One step for every ego: returns (new centre (E,2), new velocity (E,2), heading (E,), speed (E,)).
    The heading follows the velocity; a stopped vehicle keeps its heading. ``kick`` (E,2): velocity
    noise added after the relaxation (the reference simulator's outer noise, :mod:`sumo_avoid.core.noise`)."""
    new_vel, _ = relax(vel, v_des, tau_s, max_accel_mps2, dt_s)
    if kick is not None:
        new_vel = new_vel + kick
    speed = np.hypot(new_vel[:, 0], new_vel[:, 1])
    head = np.where(speed > 1e-6, np.arctan2(new_vel[:, 1], new_vel[:, 0]), np.asarray(heading, float))
    return np.asarray(pos, float) + new_vel * dt_s, new_vel, head, speed


class RelaxationActuator(HeldSpeed):
    """Velocity relaxation (``ego.actuator = "relaxation"``); outer noise from its own stream ``[seed, 7]``."""

    def __init__(self, params: RelaxationParams, ctx):
        super().__init__()
        self.p, self.dt, self.rng = params, ctx.step_s, ctx.rng(7)
        self._vel: dict[str, np.ndarray] = {}  # ego id -> 2-D velocity it holds, m/s
        self._last: tuple = ((), np.zeros((0, 2)))  # the last step's egos and their velocities (rows of _vel's)

    @staticmethod
    def steering(params: RelaxationParams) -> tuple[float, float, float]:
        """No turning radius, no yaw-rate limit: the velocity turns freely (about the centre)."""
        return 0.0, math.inf, 0.0

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        self._vel.pop(vid, None)

    def held(self, snap: Snapshot) -> Snapshot:
        ids, last = self._last
        index = snap.index
        held = self._vel
        if len(ids) == len(held) and all(v in held and v in index for v in ids):  # all held moved in the last step
            rows, w = [index[v] for v in ids], last
        else:
            known = [(index[v], w) for v, w in held.items() if v in index]
            if not known:
                return snap
            rows, w = zip(*known)
            rows, w = list(rows), np.array(w)
        vel = np.array(snap.vel)
        vel[rows] = w
        return snap.with_velocities(vel)

    def step(self, obs: Observation, command: np.ndarray) -> Motion:
        snap, rows, p = obs.snapshot, obs.ego_rows, self.p
        kick = velocity_kick(self.rng, p.outer_noise_m2ps3, self.dt, len(rows)) if p.outer_noise_m2ps3 > 0 else None
        pos, vel, head, speed = relaxation_step(snap.pos[rows], snap.vel[rows], snap.heading[rows], command,
                                                p.tau_s, p.max_accel_mps2, self.dt, kick)
        self._vel.update(zip(obs.ego_ids, vel))
        self._last = (tuple(obs.ego_ids), vel)
        self._speed.update(zip(obs.ego_ids, speed.tolist()))
        return Motion(pos, head, speed)
