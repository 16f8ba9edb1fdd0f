"""The controller protocol and what a controller is given.

A controller is built once per run from its frozen parameter dataclass, is told about each ego
when the plug-in takes it over (:class:`EgoTask`), and each step maps an :class:`Observation` to a
desired 2-D velocity per ego (m/s). It never talks to SUMO.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from sumo_avoid.core.snapshot import Snapshot


@dataclass(frozen=True)
class EgoTask:
    vid: str
    goal: np.ndarray  # (2,) m
    path: np.ndarray  # (P, 2) reference polyline along the ego's route, m
    cruise_speed_mps: float


@dataclass(frozen=True)
class Observation:
    """What the sensor hands the controllers at one step (ground truth: the whole snapshot)."""

    snapshot: Snapshot
    ego_ids: tuple[str, ...]  # egos to control, in the order of the returned velocities
    obstacles: tuple = field(default=())  # static obstacle polygons, each (k, 2) m
    # radar scans (a tuple of sensors.radar.Detections, one per mount: front[, rear]) when
    # ego.sensor = "radar", else None (use the snapshot).
    # With it, controllers take other vehicles and obstacles from it (sensors.perception), never
    # from the snapshot's other rows; Detections.target is for evaluation only.
    detections: object = field(default=None)
    # with radar: (E,) rad, aligned with ego_ids, the traffic's direction at each ego (its route's
    # nearest segment); radar returns are taken to move along it (sensors.perception)
    route_heading: object = field(default=None)

    @property
    def ego_rows(self) -> np.ndarray:
        return np.array([self.snapshot.index[v] for v in self.ego_ids], dtype=int)


class Controller(Protocol):
    def add_ego(self, task: EgoTask) -> None: ...

    def remove_ego(self, vid: str) -> None: ...

    def act(self, obs: Observation) -> np.ndarray:  # (E, 2) desired velocity, m/s
        ...

    def stats(self) -> dict:  # counters for metrics.json (e.g. SA escapes)
        ...
