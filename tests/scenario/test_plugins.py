"""Choosing and parameterising plug-ins in a scenario file (scenario/plugins.py): one ``[KIND.NAME]``
table per registered plug-in, validated whether chosen or not and kept by table name; keys of the
earlier layout refused with one line naming the new key; every scenario of the repository uses the
new layout."""
from __future__ import annotations

import pytest

from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.plugins import KINDS
from tests.conftest import SCENARIOS

OVERTAKING = SCENARIOS / "overtaking.toml"


def test_every_registered_plug_in_with_parameters_has_its_table_chosen_or_not():
    scn = scenario.load(OVERTAKING, ["ego.layers=[]", "layers.traffic.comfort_decel_mps2=2.5"])
    expected = {f"{kind}.{e.name}" for kind, reg in KINDS.items() for e in reg.entries() if e.params is not None}
    assert set(scn.tables) == expected and "sensors.truth" not in expected  # ground truth has no parameters
    assert scn.table("layers.traffic").comfort_decel_mps2 == 2.5  # the rule metrics judge by it without the layer
    assert scn.table("actuators.kinematic").min_turn_radius_m == 5.5  # the file's table
    assert scn.table("actuators.relaxation").tau_s == 1.0  # defaults where the file has none
    assert scn.params is scn.table("controllers.apf_sa") and scn.controller_params["apf"] is scn.table("controllers.apf")


def test_the_repository_s_scenarios_use_the_new_layout():
    files = [f for f in SCENARIOS.rglob("*.toml") if "[sim]" in f.read_text()]
    assert len(files) > 20
    for f in files:
        scenario.load(f)  # a key of the earlier layout would raise


@pytest.mark.parametrize("override, key, new", [
    ("radar.rear=true", "radar", "[sensors.radar]"),
    ("safety.warning_s=4.0", "safety", "[layers.danger_time]"),
    ("rules.stop_margin_m=2.0", "rules", "[layers.traffic]"),
    ('actuator.mode="relaxation"', "actuator.mode", "ego.actuator"),
    ("actuator.max_accel_mps2=2.0", "actuator", "[actuators.kinematic]"),
    ('ego.rules="none"', "ego.rules", "ego.layers"),
    ('ego.safety="danger_time"', "ego.safety", "ego.layers"),
])
def test_a_key_of_the_earlier_layout_names_the_new_one(override, key, new):
    with pytest.raises(scenario.ScenarioError) as err:
        scenario.load(OVERTAKING, [override])
    assert str(err.value).startswith(f"{OVERTAKING}: key '{key}' was renamed: use {new}")
    assert "\n" not in str(err.value)
