"""The plug-in interfaces of one rollout step, and the context a plug-in is built with.

Per step the data flows one way (:func:`sumo_avoid.rollout.loop.rollout`)::

    Snapshot --Sensor.observe--> Observation --Controller.act--> command (E, 2) m/s
             --Layer.filter (each, in order)--> command --Actuator.step--> Motion --> SUMO

Every stage is told about each ego when the plug-in takes it over (``add_ego``) and when it is
retired (``remove_ego``), and may report counters for ``metrics.json`` (``stats``). Stages are
chosen by name from the scenario through one :class:`~sumo_avoid.core.registry.Registry` per kind
(``ego.sensor``, ``ego.controller``, ``ego.layers``, ``ego.actuator``), each built as
``cls(params, context)`` with its validated ``[KIND.NAME]`` table; what assembly needs to know about
a plug-in it declares as class attributes (``needs``, ``provides_scans``, ``needs_scans``,
``monitor_when_scans``, ``steering``), never by its name.
Metrics (:class:`~sumo_avoid.metrics.base.Metric`) run afterwards on the recording, never in the loop.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import EgoTask, Keys, Motion, Needs, Observation

if TYPE_CHECKING:  # type-only (the package order puts core below road; no runtime import)
    from sumo_avoid.road.network import Road


@dataclass(frozen=True)
class Context:
    """What every plug-in may be built with (run-wide, fixed before the first step)."""

    seed: int  # the scenario seed
    step_s: float  # simulation step, s
    road: Road | None = None  # the net as data: drivable area, lanes, junctions, route paths (read-only); None in an arena
    walls: np.ndarray | None = None  # (k, 2) allowed area when the scenario has an [arena], else None
    obstacles: tuple[np.ndarray, ...] = field(default=())  # static obstacle polygons, each (k, 2) m
    turn_radius_m: float = 0.0  # the egos' smallest turning radius (the kinematic actuator's), m; 0: none
    yaw_rate_radps: float = float("inf")  # the egos' largest yaw rate (the kinematic actuator's), rad/s
    rear_axle_m: float = 0.0  # how far behind its centre an ego turns (the kinematic actuator's rear axle), m
    # the scenario's validated parameter tables by table name ("controllers.apf", "sensors.radar",
    # "layers.traffic", "actuators.kinematic", ...; every registered plug-in's, chosen or not): a plug-in
    # that works with another's parameters (a formation member with APF's, ground truth's radar for the
    # layers with the radar's) reads them here, never a default
    params: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    def rng(self, *stream: int) -> np.random.Generator:
        """The random stream of one consumer: ``default_rng(seed)`` (the controller's) or
        ``default_rng([seed, *stream])``; streams never share draws, so adding one changes no other."""
        return np.random.default_rng([self.seed, *stream] if stream else self.seed)


class EgoAware(Protocol):
    def add_ego(self, task: EgoTask) -> None: ...

    def remove_ego(self, vid: str) -> None: ...

    def stats(self) -> dict:  # counters for metrics.json: a controller's or layer's those its stats_keys declare,
        ...  # a sensor's or actuator's none ({})


class Sensor(EgoAware, Protocol):
    """Built as ``cls(params, context, *, needs_scans, v2v)``: ``needs_scans`` when a layer wants radar
    scans, ``v2v`` the controller's V2V parameters (or None)."""

    provides_scans: ClassVar[bool]  # scans with a radar for the controllers: monitor layers run (Layer.monitor_when_scans)

    def observe(self, snap: Snapshot, ego_ids: tuple[str, ...], ego_speed: np.ndarray) -> Observation: ...

    def tables(self) -> dict:  # name -> pandas DataFrame written as NAME.csv (e.g. detections)
        ...


class Controller(EgoAware, Protocol):
    """Built as ``cls(params, context)``; declares what it needs as data (``needs``)."""

    needs: ClassVar[Needs]
    metrics: ClassVar[tuple[str, ...]]  # names in sumo_avoid.metrics.METRICS computed beside the standard set
    stats_keys: ClassVar[Keys]  # the keys stats() writes (sumo_avoid.runs.declared.metric_keys)
    # optional: plots: ClassVar[tuple[str, ...]], names in sumo_avoid.plots.PLOTS drawn from its data
    # beside the standard ones (sumo_avoid.runs.declared.plot_names); none when not declared

    def act(self, obs: Observation) -> np.ndarray:  # (E, 2) desired velocity, m/s
        ...

    def tables(self) -> dict:  # name -> pandas DataFrame written as NAME.csv (ga_planner's plan log); {} if none
        ...


class Layer(EgoAware, Protocol):
    """Between controller and actuator: limits (or only watches) the command. Built as
    ``cls(params, context)`` when chosen (``ego.layers``), as ``cls(params, context, enforce=False)``
    when it runs as a monitor."""

    needs_scans: ClassVar[bool]  # wants Observation.scans (a radar on board) even with ground truth
    # not chosen, it still runs as a monitor (counters only, the command untouched) when the sensor
    # provides scans (Sensor.provides_scans)
    monitor_when_scans: ClassVar[bool]
    stats_keys: ClassVar[Keys]  # the keys stats() writes

    def filter(self, obs: Observation, command: np.ndarray) -> np.ndarray: ...


class Actuator(EgoAware, Protocol):
    """Turns commands into motion within the vehicle's limits; owns its state (held speed, velocity).
    Built as ``cls(params, context)``."""

    @staticmethod
    def steering(params: Any) -> tuple[float, float]:  # the limits controllers plan with, from its parameters:
        ...  # (smallest turning radius, m; largest yaw rate, rad/s); (0.0, inf) for none (Context)

    def held(self, snap: Snapshot) -> Snapshot:  # the snapshot with what the actuator knows better
        ...

    def speeds(self, snap: Snapshot, ego_ids: tuple[str, ...]) -> np.ndarray:  # (E,) signed, m/s
        ...

    def step(self, obs: Observation, command: np.ndarray) -> Motion: ...


class SetupHook(Protocol):
    """Something done once, after SUMO started and before the first step (spawn, polygons)."""

    def setup(self, sim: Any) -> None: ...


class Callback(Protocol):
    """Watches the loop (progress, timing, plots); never changes what happens."""

    def on_step(self, snap: Snapshot, n_steps: int) -> None: ...

    def on_end(self) -> None: ...
