"""Defaults every controller may start from (:class:`BaseController`), so that a new controller is
its ``act()``, its parameter dataclass and one registry line (docs/writing_a_controller.md)."""
from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from sumo_avoid.core.types import EgoTask, Keys, Needs, Observation
from sumo_avoid.sensing.v2v import V2VParams


class BaseController:
    """A controller of :class:`sumo_avoid.core.interfaces.Controller` with the defaults: egos are
    retired at their goal (``needs``), no metrics or plots of its own, no ``metrics.json`` keys
    (``stats_keys``, ``stats()``), no tables; ``add_ego`` keeps each ego's task in ``self.tasks``
    (by id), ``remove_ego`` drops it; an ideal V2V link (no delay, no noise) if ``needs.v2v``.
    The parameters are ``self.p``. A subclass writes ``act()`` and overrides what differs."""

    needs: ClassVar[Needs] = Needs()
    metrics: ClassVar[tuple[str, ...]] = ()  # names in sumo_avoid.metrics.METRICS beside the standard set
    stats_keys: ClassVar[Keys] = Keys()  # the metrics.json keys stats() writes
    plots: ClassVar[tuple[str, ...]] = ()  # names in sumo_avoid.plots.PLOTS drawn beside the standard ones

    def __init__(self, params: Any, ctx: Any = None):
        self.p = params
        self.tasks: dict[str, EgoTask] = {}

    def add_ego(self, task: EgoTask) -> None:
        self.tasks[task.vid] = task

    def remove_ego(self, vid: str) -> None:
        self.tasks.pop(vid, None)

    def stats(self) -> dict:
        return {}

    def tables(self) -> dict:
        return {}

    def v2v_params(self) -> V2VParams:
        return V2VParams()

    def act(self, obs: Observation) -> np.ndarray:  # (E, 2) desired velocity, m/s
        raise NotImplementedError(f"{type(self).__name__}.act")
