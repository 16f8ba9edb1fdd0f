"""What a run leaves behind: the recording and what the metrics need to read it."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pandas as pd


@dataclass(frozen=True)
class Scene:
    """The static world of a run: the road (sumo_avoid.road.network.Road), an arena's walls, obstacles."""

    road: Any
    walls: np.ndarray | None = None  # (k, 2) arena square, or None on a road
    obstacles: tuple[np.ndarray, ...] = ()  # static obstacle polygons, each (k, 2) m


@dataclass(frozen=True)
class RunResult:
    scenario: Any  # sumo_avoid.scenario.spec.Scenario
    scene: Scene
    traj: pd.DataFrame  # one row per recorded vehicle per step (rollout.recorder); persons apart (persons)
    sumo_events: pd.DataFrame  # SUMO's own collision reports
    goals: dict  # ego id -> (x, y)
    steps: int
    sim_time_s: float
    stats: dict  # the plug-ins' counters (controller, layers, sensor, actuator)
    timings: dict = field(default_factory=dict)
    tables: dict = field(default_factory=dict)  # name -> DataFrame, written as NAME.csv (e.g. detections)
    tasks: dict = field(default_factory=dict)  # ego id -> EgoTask (route path, junction links, speed limits)
    signals: pd.DataFrame | None = None  # traffic light states: time_s, tls, state (a row per change)
    ssm: Any = None  # sumo_avoid.sumo.ssm_device.SsmParams SUMO's SSM device ran with (conflicts in tables), None: off
    persons: pd.DataFrame | None = None  # one row per recorded person per step, columns as traj (rollout.recorder)
    classes: dict = field(default_factory=dict)  # id -> SUMO vehicle class of every recorded road user
    # ego id -> time of its last recorded step, s: egos SUMO's driver drove to their route's end, their goal
    # (controller "sumo"; rollout.egos.EgoBook.arrivals): they reached it (metrics.basic.motion_summary)
    arrivals: dict = field(default_factory=dict)
    detours: dict = field(default_factory=dict)  # ego id -> (its route, the one it drove round U-turns) (EgoBook)
    _memo: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def road(self):
        return self.scene.road

    def memo(self, key: str, compute: Callable[[], Any]) -> Any:
        """A value several metrics share (e.g. phi_coll), computed once per run."""
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]
