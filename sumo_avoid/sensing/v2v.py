"""V2V for a flock (SPEC §1.3, seed 000's reference simulator): what each member knows of itself and
receives from the others, with communication delay, Gaussian noise and the drifting GPS error.

The controller calls :meth:`V2VLink.states` when it updates (every ``update_period_s``): the link
keeps the messages of the last ``delay_s`` and hands out the ones sent ``delay_s`` ago. The noise
draws come from the link's own random stream in a fixed order (GPS walk, then own position, own
velocity, neighbours' positions, neighbours' velocities).
"""
from __future__ import annotations

import collections
import math
from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.noise import DampedRandomWalk
from sumo_avoid.core.snapshot import Snapshot


@dataclass(frozen=True)
class V2VParams:
    delay_s: float = 0.0  # neighbours' states arrive this late, s
    pos_noise_m: float = 0.0  # std of Gaussian noise on sensed positions, m
    vel_noise_mps: float = 0.0  # std of Gaussian noise on sensed velocities, m/s
    gps_sigma_m2ps2: float = 0.0  # reference simulator's GPS error (damped random walk), 0 = off
    gps_lambda_ps: float = 0.1  # its damping, 1/s
    update_period_s: float = 0.0  # the controller's update period (the GPS walk's smallest step), s


class V2VLink:
    def __init__(self, params: V2VParams, rng: np.random.Generator):
        self.p = params
        self.rng = rng
        self._history: collections.deque = collections.deque()
        self._gps: DampedRandomWalk | None = None
        self._gps_time = -math.inf
        self._gps_keys: list = []  # the walks' keys for the rows of (ids, rows) in _keys_for
        self._keys_for: tuple = (None, None)

    def states(self, snap: Snapshot, rows_now: np.ndarray):
        """Own state now, neighbours' state delay_s ago (+ noise); rows aligned with ``rows_now``."""
        p = self.p
        self._history.append((snap.time_s, snap.ids, snap.pos, snap.vel))
        while len(self._history) > 1 and self._history[1][0] <= snap.time_s - p.delay_s + 1e-9:
            self._history.popleft()
        t0, ids0, pos0, vel0 = self._history[0]
        own_pos, own_vel = snap.pos[rows_now].copy(), snap.vel[rows_now].copy()
        if ids0 is snap.ids or ids0 == snap.ids:
            nb_pos, nb_vel = pos0[rows_now].copy(), vel0[rows_now].copy()
        else:
            idx0 = {v: k for k, v in enumerate(ids0)}
            r0 = np.array([idx0.get(snap.ids[r], -1) for r in rows_now])
            have = r0 >= 0
            nb_pos = np.where(have[:, None], pos0[np.maximum(r0, 0)], own_pos)
            nb_vel = np.where(have[:, None], vel0[np.maximum(r0, 0)], own_vel)
        if p.gps_sigma_m2ps2 > 0:  # the reference simulator's drifting GPS error (core.noise)
            if self._gps is None:
                self._gps = DampedRandomWalk(p.gps_sigma_m2ps2, p.gps_lambda_ps, self.rng)
            if not (snap.ids is self._keys_for[0] and np.array_equal(rows_now, self._keys_for[1])):
                keys = [snap.ids[r] for r in rows_now]  # (the same list while the rows do not change)
                self._gps_keys = [(k, 0) for k in keys] + [(k, 1) for k in keys]
                self._keys_for = (snap.ids, rows_now.copy())
            dt = max(p.update_period_s, snap.time_s - self._gps_time if math.isfinite(self._gps_time) else 0.0)
            self._gps_time = snap.time_s
            x, u = self._gps.step(self._gps_keys, dt)
            e = len(rows_now)
            own_pos, own_vel, nb_pos, nb_vel = own_pos + x[:e], own_vel + u[:e], nb_pos + x[e:], nb_vel + u[e:]
        if p.pos_noise_m > 0 or p.vel_noise_mps > 0:
            e = len(rows_now)
            own_pos += self.rng.normal(0.0, p.pos_noise_m, (e, 2))
            own_vel += self.rng.normal(0.0, p.vel_noise_mps, (e, 2))
            nb_pos += self.rng.normal(0.0, p.pos_noise_m, (e, 2))
            nb_vel += self.rng.normal(0.0, p.vel_noise_mps, (e, 2))
        return own_pos, own_vel, nb_pos, nb_vel
