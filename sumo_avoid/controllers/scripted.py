"""``scripted``: drive straight ahead at a fixed speed, blind to everything.

Used to check that the plug-in really sees a commanded crash (SUMO's safety is off for egos).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..config import field_doc
from .base import EgoTask, Observation


@dataclass(frozen=True)
class ScriptedParams:
    speed_mps: float = field_doc(10.0, doc="commanded speed, m/s")
    direction_deg: float | None = field_doc(None, signed=True,
                                            doc="commanded direction, degrees CCW from +x (default: initial heading)")


class ScriptedController:
    def __init__(self, params: ScriptedParams, road=None, rng=None):
        self.p = params
        self._dir: dict[str, float] = {}

    def add_ego(self, task: EgoTask) -> None:
        self._dir[task.vid] = math.nan if self.p.direction_deg is None else math.radians(self.p.direction_deg)

    def remove_ego(self, vid: str) -> None:
        self._dir.pop(vid, None)

    def act(self, obs: Observation) -> np.ndarray:
        rows = obs.ego_rows
        out = np.zeros((len(rows), 2))
        for k, (vid, r) in enumerate(zip(obs.ego_ids, rows)):
            if math.isnan(self._dir[vid]):
                self._dir[vid] = float(obs.snapshot.heading[r])
            out[k] = self.p.speed_mps * np.array([math.cos(self._dir[vid]), math.sin(self._dir[vid])])
        return out

    def stats(self) -> dict:
        return {}
