"""From a validated scenario to the plug-ins of one run, each chosen by name through its registry
and built with its validated ``[KIND.NAME]`` table (``scn.table``).

Choices made here (data, so the loop never asks):

* the controller is ``ego.controller`` (:data:`sumo_avoid.control.CONTROLLERS`), built with the
  scenario's ``[controllers.NAME]`` parameters and the controller's random stream ``default_rng(seed)``;
* the layers are ``ego.layers`` in that order (:data:`sumo_avoid.safety.LAYERS`, default
  ``["traffic"]``); when the sensor declares ``provides_scans``, every layer that declares
  ``monitor_when_scans`` and was not chosen runs after them as a monitor (``enforce=False``: its
  counters in metrics.json, the command untouched) — the danger-time layer with the radar; none
  when the controller leaves the egos to SUMO (``Needs(drives=False)``, controller ``sumo``);
* the sensor is ``ego.sensor`` (:data:`sumo_avoid.sensing.SENSORS`); it carries a front radar
  (stream ``[seed, 4]``, a rear one on ``[seed, 5]``) when it is the radar or a layer needs scans,
  and the V2V link (stream ``default_rng(seed)``) when the controller declares ``Needs(v2v=True)``;
* the actuator is ``ego.actuator`` (:data:`sumo_avoid.actuation.ACTUATORS`, outer noise on
  ``[seed, 7]``); its ``steering`` gives the turning limits controllers plan with (:func:`context`).
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

from sumo_avoid.actuation import ACTUATORS
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.interfaces import Actuator, Context, Controller, Layer, Sensor
from sumo_avoid.core.registry import Entry
from sumo_avoid.core.types import EgoTask
from sumo_avoid.safety import LAYERS
from sumo_avoid.sensing import SENSORS


@dataclass(frozen=True)
class Stack:
    sensor: Sensor
    controller: Controller
    layers: tuple[Layer, ...]
    actuator: Actuator

    @property
    def stages(self) -> tuple:
        return (self.sensor, self.controller, *self.layers, self.actuator)

    def add_ego(self, task: EgoTask) -> None:
        for stage in self.stages:
            stage.add_ego(task)

    def remove_ego(self, vid: str) -> None:
        for stage in self.stages:
            stage.remove_ego(vid)

    def stats(self) -> dict:
        out: dict = {}
        for stage in (self.controller, *self.layers, self.sensor, self.actuator):
            out.update(stage.stats())
        return out

    def tables(self) -> dict:
        """The sensor's tables and the controller's (ga_planner's plan log)."""
        return {**self.sensor.tables(), **self.controller.tables()}


def context(scn, step_s: float, road=None, walls=None, obstacles=()) -> Context:
    """The run's :class:`Context`: the steering limits of the chosen actuator (its ``steering``)
    and every validated table of the scenario by name (``Context.params``)."""
    ego = scn.spec.ego
    steer = ACTUATORS[ego.actuator].factory.steering(scn.tables.get(f"actuators.{ego.actuator}"))
    return Context(scn.spec.sim.seed, step_s, road, walls, obstacles, *steer, params=MappingProxyType(dict(scn.tables)))


def controller_for(scn, ctx: Context) -> Controller:
    entry = CONTROLLERS[scn.spec.ego.controller]
    return entry.factory(scn.params, ctx)


def layer_plan(scn) -> tuple[tuple[Entry, object, dict], ...]:
    """The layers of a run, in order: (registry entry, its parameters, keyword arguments); none
    when the controller leaves the egos to SUMO (``Needs(drives=False)``: there is no command to limit)."""
    ego = scn.spec.ego
    if not CONTROLLERS[ego.controller].factory.needs.drives:
        return ()
    plan = [(LAYERS[name], scn.tables.get(f"layers.{name}"), {}) for name in ego.layers]
    if SENSORS[ego.sensor].factory.provides_scans:
        plan += [(e, scn.tables.get(f"layers.{e.name}"), {"enforce": False}) for e in LAYERS.entries()
                 if e.factory.monitor_when_scans and e.name not in ego.layers]
    return tuple(plan)


def assemble(scn, ctx: Context, controller: Controller) -> Stack:
    ego = scn.spec.ego
    layers = [entry.factory(params, ctx, **kw) for entry, params, kw in layer_plan(scn)]
    needs_scans = any(type(layer).needs_scans for layer in layers)
    sensor = SENSORS[ego.sensor].factory(scn.tables.get(f"sensors.{ego.sensor}"), ctx, needs_scans=needs_scans,
                                         v2v=controller.v2v_params() if type(controller).needs.v2v else None)
    actuator = ACTUATORS[ego.actuator].factory(scn.tables.get(f"actuators.{ego.actuator}"), ctx)
    return Stack(sensor, controller, tuple(layers), actuator)
