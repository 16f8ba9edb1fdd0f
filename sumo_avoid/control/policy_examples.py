"""Scripted policies on the observation vector (:mod:`sumo_avoid.control.policy_obs`), for the
``policy`` controller (``controllers.policy.policy = "sumo_avoid.control.policy_examples:KeepLane"``)
and the Gymnasium environment: a baseline to compare a trained policy with, and the example of
docs/gym.md. Velocity actions (v_s, v_d), m/s; the default observation layout (8 road users)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.control.policy_obs import EGO, GOAL, OTHER, ROUTE

#: Where the road users start in the vector of ``route_points`` points ahead.
ROUTE_POINTS = 10


@dataclass(frozen=True)
class KeepLane:
    """Follow the lane at ``cruise_speed_mps``, steering back to its centre (``gain_per_s`` x d), and keep
    ``headway_s`` behind the nearest road user ahead in the lane (within ``lane_half_width_m`` across)."""

    cruise_speed_mps: float = 15.0
    gain_per_s: float = 0.5
    headway_s: float = 1.5
    min_gap_m: float = 5.0
    lane_half_width_m: float = 1.8
    ego_half_length_m: float = 2.5
    route_points: int = ROUTE_POINTS

    def __call__(self, observation) -> np.ndarray:
        x = np.asarray(observation, float)
        d = x[EGO.index("d_m")]
        start = len(EGO) + len(GOAL) + len(ROUTE) * self.route_points
        others = x[start:].reshape(-1, len(OTHER))
        present, ds, dd = others[:, 0] > 0.5, others[:, 1], others[:, 2]
        ahead = present & (ds > 0.0) & (np.abs(dd) < self.lane_half_width_m)
        v = self.cruise_speed_mps
        if ahead.any():
            k = int(np.argmin(np.where(ahead, ds, np.inf)))
            v_lead = max(x[EGO.index("v_s_mps")] + others[k, 3], 0.0)
            gap = ds[k] - 0.5 * others[k, 5] - self.ego_half_length_m - self.min_gap_m  # bumper to bumper
            v = float(np.clip(min(v, v_lead + gap / self.headway_s), 0.0, v))
        return np.array([v, -self.gain_per_s * d])
