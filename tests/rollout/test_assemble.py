"""Assembly from declarations (no SUMO): the layers of a run from ``ego.layers`` and what the sensor and
layers declare (``provides_scans``, ``monitor_when_scans``), the Context's steering limits from the
actuator's ``steering`` and its tables by name, never a plug-in's name (the plots: tests/runs/test_declared.py)."""
from __future__ import annotations

import math

import pytest

from sumo_avoid.rollout.assemble import context, layer_plan
from sumo_avoid.runs.declared import metric_keys
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.sensing import SENSORS
from sumo_avoid.sensing.sensors import TruthSensor
from tests.conftest import SCENARIOS

OVERTAKING = SCENARIOS / "overtaking.toml"


def plan(scn) -> list[tuple[str, dict]]:
    return [(entry.name, kw) for entry, _, kw in layer_plan(scn)]


class ScanningTruth(TruthSensor):
    """A toy sensor that declares it provides scans (nothing else changes)."""

    provides_scans = True


@pytest.fixture
def scanning_sensor():
    SENSORS.register("scanning", ScanningTruth)
    yield
    SENSORS.unregister("scanning")


def test_the_layers_are_ego_layers_in_order_and_the_monitor_follows_the_sensor_s_declaration(scanning_sensor):
    assert plan(scenario.load(OVERTAKING)) == [("traffic", {})]  # the default: rules on, no safety layer
    assert plan(scenario.load(OVERTAKING, ["ego.layers=[]"])) == []
    both = scenario.load(OVERTAKING, ['ego.layers=["danger_time", "traffic"]'])
    assert plan(both) == [("danger_time", {}), ("traffic", {})]  # in the order given
    # a sensor that provides scans: danger_time (monitor_when_scans) counts when not chosen
    for sensor in ("radar", "scanning"):
        scn = scenario.load(OVERTAKING, [f'ego.sensor="{sensor}"'])
        assert plan(scn) == [("traffic", {}), ("danger_time", {"enforce": False})]
        assert {"radar_warnings", "radar_brakes"} <= metric_keys(scn).names
        chosen = scenario.load(OVERTAKING, [f'ego.sensor="{sensor}"', 'ego.layers=["traffic", "danger_time"]'])
        assert plan(chosen) == [("traffic", {}), ("danger_time", {})]
    assert "radar_warnings" not in metric_keys(scenario.load(OVERTAKING)).names


def test_the_layers_get_their_tables_also_when_they_only_monitor():
    scn = scenario.load(OVERTAKING, ['ego.sensor="radar"', "layers.danger_time.warning_s=4.0",
                                     "layers.traffic.stop_margin_m=2.0"])
    params = {entry.name: p for entry, p, _ in layer_plan(scn)}
    assert params["danger_time"].warning_s == 4.0 and params["traffic"].stop_margin_m == 2.0


def test_the_context_has_the_actuator_s_steering_limits_and_every_table():
    car = scenario.load(OVERTAKING)
    ctx = context(car, 0.1)
    assert (ctx.turn_radius_m, ctx.yaw_rate_radps) == (5.5, 0.8)  # overtaking's [actuators.kinematic]
    assert {"controllers.apf_sa", "sensors.radar", "layers.traffic", "layers.danger_time", "actuators.kinematic",
            "actuators.relaxation"} <= set(ctx.params)
    assert ctx.params["actuators.kinematic"] is car.table("actuators.kinematic")
    relax = context(scenario.load(OVERTAKING, ['ego.actuator="relaxation"']), 0.1)
    assert (relax.turn_radius_m, relax.yaw_rate_radps) == (0.0, math.inf)
