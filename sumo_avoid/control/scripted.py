"""``scripted``: drive straight ahead at a fixed speed, blind to everything.

Used to check that the plug-in really sees a commanded crash (SUMO's safety is off for egos):
each ego keeps its initial heading (or ``direction_deg``) at ``speed_mps``; an ego named in
``stop_after_m`` stops for good once it has covered that distance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.types import EgoTask, Observation


@dataclass(frozen=True)
class ScriptedParams:
    speed_mps: float = field_doc(10.0, doc="commanded speed, m/s")
    direction_deg: float | None = field_doc(None, signed=True,
                                            doc="commanded direction, degrees CCW from +x (default: initial heading)")
    stop_after_m: dict = field_doc(default_factory=dict,
                                   doc="{ego id = distance in m}: that ego stops once it has covered the distance")

    def __post_init__(self):
        for k, v in self.stop_after_m.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise ValueError(f"controllers.scripted.stop_after_m.{k}: a non-negative distance in m, got {v!r}")


class ScriptedController(BaseController):
    """Straight ahead at a fixed speed, blind (for crash tests)."""

    def __init__(self, params: ScriptedParams, ctx=None):
        super().__init__(params, ctx)
        self._dir: dict[str, float] = {}
        self._start: dict[str, np.ndarray] = {}

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        self._dir[task.vid] = math.nan if self.p.direction_deg is None else math.radians(self.p.direction_deg)

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        self._dir.pop(vid, None)
        self._start.pop(vid, None)

    def act(self, obs: Observation) -> np.ndarray:
        snap = obs.snapshot
        for vid, r in zip(obs.ego_ids, obs.ego_rows):
            if math.isnan(self._dir[vid]):
                self._dir[vid] = float(snap.heading[r])
        d = np.array([self._dir[v] for v in obs.ego_ids], dtype=float)
        out = self.p.speed_mps * np.column_stack([np.cos(d), np.sin(d)]) if len(d) else np.zeros((0, 2))
        for k, (vid, r) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            limit = self.p.stop_after_m.get(vid)
            if limit is not None:
                start = self._start.setdefault(vid, snap.pos[r].copy())
                if np.hypot(*(snap.pos[r] - start)) >= limit:
                    out[k] = 0.0
        return out
