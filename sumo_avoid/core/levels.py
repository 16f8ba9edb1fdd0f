"""Levels: bridges and tunnels. SUMO gives every lane a shape with z and every road user a z (the
z of its position on its lane, ``vehicle.getPosition3D`` / ``person.getPosition3D``); the snapshot
carries it (:attr:`~sumo_avoid.core.snapshot.Snapshot.z`), and so does the recording (column ``z``,
written when a run has any z other than 0).

Two road users are on the *same level* when their z differ by at most
:attr:`Levels.clearance_m`; otherwise one passes over the other (a bridge, a tunnel) and neither is an
obstacle for the other (the sensors -- ground truth and radar: a radar does not see through a
bridge deck -- and the controllers), nor a collision, a gap or a TTC pair for the metrics.
On a flat net (every z 0) everyone is on one level and nothing changes.

The threshold: a road bridge leaves a vertical clearance of at least about 4.5 m under it (4.5 m to
5.1 m in most European and US standards), plus its deck, so road users on two levels are at least
~5.5 m apart in z; on one road, two road users close enough to matter are never 4 m apart in z (a
steep 10 % ramp rises 1 m over 10 m). 4 m lies between.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Levels:
    clearance_m: float = 4.0  # |z_a - z_b| above this: on two levels (a bridge over a road), m


LEVELS = Levels()


def same_level(z_a, z_b, levels: Levels = LEVELS) -> np.ndarray:
    """Elementwise: whether road users at heights ``z_a`` and ``z_b`` (m) share a level."""
    return np.abs(np.asarray(z_a, float) - np.asarray(z_b, float)) <= levels.clearance_m


def has_levels(z, levels: Levels = LEVELS) -> bool:
    """Whether heights ``z`` (m) span more than one level (else every level test is true)."""
    z = np.asarray(z, float)
    return bool(z.size) and float(np.ptp(z)) > levels.clearance_m
