"""What both actuators share: each ego's signed speed as the actuator last set it (SUMO cannot
report a reversing speed, nor an off-lane vehicle's speed reliably); SUMO's until the first step."""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import EgoTask


class HeldSpeed:
    def __init__(self):
        self._speed: dict[str, float] = {}  # ego id -> signed speed (NaN: not moved yet), m/s

    def add_ego(self, task: EgoTask) -> None:
        self._speed[task.vid] = np.nan

    def remove_ego(self, vid: str) -> None:
        self._speed.pop(vid, None)

    def stats(self) -> dict:
        return {}

    def speeds(self, snap: Snapshot, ego_ids) -> np.ndarray:
        held = np.array([self._speed[v] for v in ego_ids])
        if not np.isnan(held).any():  # every ego moved already (SUMO's speeds are needed only before that)
            return held
        return np.where(np.isnan(held), snap.speed[[snap.index[v] for v in ego_ids]], held)
