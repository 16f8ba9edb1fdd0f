"""Noise of the flocking model's reference simulator (robotsim: github.com/csviragh/robotsim,
``parameters/unitparams.dat``, ``src/robotmodel.c``, ``src/sensors.c``), measured to matter for
Table 4 in ``reports/table4/investigation.md``. SPEC §1.3 only says "small noise"; these are the
reference simulator's own two kinds, with its default amplitudes (not tuned here):

* **outer noise** (``actuator.outer_noise_m2ps3``, robotsim ``Sigma_outer_XY`` = 2000 cm²/s³ =
  0.2 m²/s³): white acceleration noise on the *actual* motion, a velocity kick of standard
  deviation sqrt(2 σ dt) per component every step (:func:`velocity_kick`);
* **GPS error** (``controllers.flocking.gps_sigma_m2ps2``, robotsim ``Sigma_GPS_XY`` = 50 cm²/s² =
  0.005 m²/s²): a damped random walk per vehicle and component (:class:`DampedRandomWalk`), one
  for what a vehicle reads of itself and one for what its neighbours receive; stationary spread
  about 0.7 m and 0.07 m/s with λ = 0.1 1/s.
"""
from __future__ import annotations

import math

import numpy as np


def velocity_kick(rng: np.random.Generator, sigma_m2ps3: float, dt_s: float, n: int) -> np.ndarray:
    """(n, 2) velocity increments, m/s: N(0, 2 σ dt) per component."""
    return rng.normal(0.0, math.sqrt(2.0 * sigma_m2ps3 * dt_s), (n, 2))


class DampedRandomWalk:
    """Per-key 2-D error x (m) with rate u (m/s), stepped every ``dt_s``:
    u += sqrt(2 λ dt σ) ξ - k x dt - λ dt u,  x += u dt,  k = sqrt(2 λ σ) / 3, ξ ~ N(0, 1)."""

    def __init__(self, sigma_m2ps2: float, lambda_ps: float, rng: np.random.Generator):
        self.sigma, self.lam, self.rng = sigma_m2ps2, lambda_ps, rng
        self.k = math.sqrt(2.0 * lambda_ps * sigma_m2ps2) / 3.0
        self._row: dict = {}  # key -> row of x, u
        self.x = np.zeros((0, 2))
        self.u = np.zeros((0, 2))
        self._keys: list = []  # the last call's keys and their rows
        self._r = np.zeros(0, dtype=int)

    def step(self, keys, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Advance the walks of ``keys`` (new keys start at 0) by dt_s; return their (x, u), (n, 2)."""
        if keys is not self._keys and keys != self._keys:  # the last call's keys keep their rows
            new = [k for k in keys if k not in self._row]
            for k in new:
                self._row[k] = len(self._row)
            if new:
                self.x = np.concatenate([self.x, np.zeros((len(new), 2))])
                self.u = np.concatenate([self.u, np.zeros((len(new), 2))])
            self._keys, self._r = keys, np.array([self._row[k] for k in keys], dtype=int)
        r = self._r
        xi = self.rng.normal(0.0, 1.0, (len(r), 2))
        x, u = self.x[r], self.u[r]
        u = u + xi * math.sqrt(2.0 * self.lam * dt_s * self.sigma) - self.k * x * dt_s - self.lam * dt_s * u
        x = x + u * dt_s
        self.x[r], self.u[r] = x, u
        return x, u
