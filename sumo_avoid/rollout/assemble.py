"""From a validated scenario to the plug-ins of one run, each chosen by name through its registry.

Choices made here (data, so the loop never asks):

* the controller is ``ego.controller`` (:data:`sumo_avoid.control.CONTROLLERS`), built with the
  scenario's ``[controllers.NAME]`` parameters and the controller's random stream ``default_rng(seed)``;
* the layers: ``ego.rules`` (:data:`sumo_avoid.safety.RULES`, default "traffic") first, then ``ego.safety`` (:data:`sumo_avoid.safety.LAYERS`, "none" = no layer); with a radar
  on board (``ego.sensor = "radar"``) and no layer, the danger-time layer still runs as a monitor
  (its counters in metrics.json, the command untouched), as before the plug-ins;
* the sensor is ``ego.sensor`` (:data:`sumo_avoid.sensing.SENSORS`); it carries a front radar
  (stream ``[seed, 4]``, a rear one on ``[seed, 5]``) when it is the radar or a layer needs scans,
  and the V2V link (stream ``default_rng(seed)``) when the controller declares ``Needs(v2v=True)``;
* the actuator is ``actuator.mode`` (:data:`sumo_avoid.actuation.ACTUATORS`, outer noise on ``[seed, 7]``).
"""
from __future__ import annotations

from dataclasses import dataclass

from sumo_avoid.actuation import ACTUATORS
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.interfaces import Actuator, Context, Controller, Layer, Sensor
from sumo_avoid.core.registry import Entry
from sumo_avoid.core.types import EgoTask, Keys
from sumo_avoid.metrics import STANDARD, declared_keys
from sumo_avoid.safety import LAYERS, RULES
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


def controller_for(scn, ctx: Context) -> Controller:
    entry = CONTROLLERS[scn.spec.ego.controller]
    return entry.factory(scn.params, ctx)


def layer_plan(spec) -> tuple[tuple[Entry, object, dict], ...]:
    """The layers of a run, in order: (registry entry, its parameters, keyword arguments)."""
    plan = []
    if spec.ego.rules != "none":
        plan.append((RULES[spec.ego.rules], spec.rules, {}))
    if spec.ego.safety != "none":
        plan.append((LAYERS[spec.ego.safety], spec.safety, {"enforce": True}))
    elif spec.ego.sensor == "radar":
        plan.append((LAYERS["danger_time"], spec.safety, {"enforce": False}))
    return tuple(plan)


def assemble(scn, ctx: Context, controller: Controller) -> Stack:
    spec = scn.spec
    layers = [entry.factory(params, ctx, **kw) for entry, params, kw in layer_plan(spec)]
    needs_scans = any(type(layer).needs_scans for layer in layers)
    sensor = SENSORS[spec.ego.sensor].factory(spec.radar, ctx, needs_scans=needs_scans,
                                              v2v=controller.v2v_params() if type(controller).needs.v2v else None)
    actuator = ACTUATORS[spec.actuator.mode].factory(spec.actuator, ctx)
    return Stack(sensor, controller, tuple(layers), actuator)


def metric_names(scn) -> tuple[str, ...]:
    """The standard set (the summary, plots, ledger and suites read it), what the controller declares
    (``metrics``), then what the scenario adds (``output.metrics``); each once, in that order."""
    names = STANDARD + CONTROLLERS[scn.spec.ego.controller].factory.metrics + scn.spec.output.metrics
    return tuple(dict.fromkeys(names))


def metric_keys(scn) -> Keys:
    """Every key a run of ``scn`` can write to ``metrics.json``, from the declarations alone (nothing
    runs): the keys of its metrics (:func:`metric_names`), the plug-ins' counters among them (the
    ``stats_keys`` of its controller and layers; sensors and actuators write none)."""
    stats = Keys()
    for cls in (CONTROLLERS[scn.spec.ego.controller].factory, *(e.factory for e, _, _ in layer_plan(scn.spec))):
        stats = stats | cls.stats_keys
    return declared_keys(metric_names(scn), scn, stats)
