"""Plug-ins found by name (core/registry.py): built in, then an entry point of the kind's group, then
an import path MODULE:ATTR; the plug-in's ``Params`` (frozen) validated like a built-in's table;
each way of not finding one says why in one line. A toy distribution (its dist-info, as an
installer writes it) and modules in tmp_path, on sys.path for the test only."""
from __future__ import annotations

import sys
import textwrap

import pytest

from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import ScenarioError
from sumo_avoid.core.registry import BUILT_IN, IMPORT_PATH, PluginNotFound, Registry
from sumo_avoid.metrics import METRICS
from sumo_avoid.runs.declared import metric_keys
from sumo_avoid.safety import LAYERS
from sumo_avoid.scenario import spec as scenario
from tests.conftest import SCENARIOS

TOY = '''
    from dataclasses import dataclass

    import numpy as np

    from sumo_avoid.control.base_controller import BaseController
    from sumo_avoid.core.config import field_doc
    from sumo_avoid.core.types import Keys
    from sumo_avoid.metrics.base import Metric
    from sumo_avoid.safety.traffic import TrafficRulesLayer


    @dataclass(frozen=True)
    class ToyParams:
        gain: float = field_doc(1.0, positive=True, doc="a gain")


    class Toy(BaseController):
        """A toy controller."""
        Params = ToyParams

        def act(self, obs):
            return np.zeros((len(obs.ego_ids), 2))


    @dataclass
    class Loose:
        gain: float = 1.0


    class Unfrozen(Toy):
        Params = Loose


    class ToyMetric(Metric):
        keys = Keys(("toy_score",))

        def compute(self, run):
            return {"toy_score": 1.0}


    class ToyLayer(TrafficRulesLayer):
        """A toy layer with parameters of its own."""
        Params = ToyParams


    NOT_A_CLASS = 3
'''
ENTRY_POINTS = '''
    [sumo_avoid.controllers]
    toy = toyplug:Toy
    apf = toyplug:Toy
    broken = toybroken:Anything
    [sumo_avoid.metrics]
    toy_metric = toyplug:ToyMetric
'''


@pytest.fixture
def toy(tmp_path, monkeypatch):
    (tmp_path / "toyplug.py").write_text(textwrap.dedent(TOY))
    (tmp_path / "toybroken.py").write_text("raise RuntimeError('half-installed')\n")
    dist = tmp_path / "toyplug-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: toyplug\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(textwrap.dedent(ENTRY_POINTS))
    monkeypatch.syspath_prepend(str(tmp_path))
    yield
    for reg in (CONTROLLERS, METRICS, LAYERS):
        reg._found.clear()
    for name in ("toyplug", "toybroken"):
        sys.modules.pop(name, None)


def test_built_in_then_entry_point_then_import_path(toy):
    reg = Registry("controller")
    reg.register("apf", object)
    assert reg.find("apf").origin == BUILT_IN  # a built-in wins over an entry point of its name
    toy_ep, toy_path = reg.find("toy"), reg.find("toyplug:Toy")
    assert toy_ep.origin == "entry point (toyplug)" and toy_path.origin == IMPORT_PATH
    assert toy_ep.factory is toy_path.factory and toy_ep.params.__name__ == "ToyParams"
    assert reg.find("toy") is toy_ep and "toy" in reg and "toy" not in reg.names()  # cached, not registered
    listed = {name: (origin, found) for name, origin, found in reg.installed()}
    assert "shadowed" in listed["apf"][1] and listed["toy"][1] is toy_ep and "half-installed" in listed["broken"][1]


@pytest.mark.parametrize("name, says", [
    ("nothing", "no controller of that name, built in or an entry point of group sumo_avoid.controllers"),
    ("broken", "cannot be loaded: RuntimeError: half-installed"),
    ("toyplug:Toi", "module 'toyplug' has no attribute 'Toi'"),
    ("toyplg:Toy", "cannot import 'toyplg': ModuleNotFoundError: No module named 'toyplg'"),
    ("toybroken:X", "cannot import 'toybroken': RuntimeError: half-installed"),
    ("toyplug:NOT_A_CLASS", "toyplug:NOT_A_CLASS is not a controller class or function (a int)"),
    ("toyplug:Unfrozen", "toyplug:Unfrozen.Params is not a frozen dataclass"),
    ("toyplug:", "an import path is MODULE:ATTR"),
])
def test_not_found_says_why(toy, name, says):
    with pytest.raises(PluginNotFound) as err:
        Registry("controller").find(name)
    assert says in str(err.value) and "\n" not in str(err.value)
    assert name not in Registry("controller")


def test_a_scenario_chooses_validates_and_declares_them(toy):
    scn = scenario.load(SCENARIOS / "overtaking.toml", ["ego.controller=toy", "controllers.toy.gain=2.5",
                                                        'ego.layers=["traffic", "toyplug:ToyLayer"]',
                                                        'output.metrics=["toy_metric"]'])
    assert scn.params.gain == 2.5 and scn.table("layers.toyplug:ToyLayer").gain == 1.0
    assert "toy_score" in metric_keys(scn).numeric
    assert "controllers.apf_sa" in scn.tables  # the built-ins' tables as ever


@pytest.mark.parametrize("overrides, key, says", [
    (["ego.controller=toy", "controllers.toy.gain=-1"], "controllers.toy.gain", "positive"),
    (["ego.controller=toy", "controllers.toy.gian=1"], "controllers.toy.gian", "known keys"),
    (["ego.controller=toyplug:Toi"], "ego.controller", "has no attribute 'Toi'"),
    (['output.metrics=["toyplug:NoMetric"]'], "output.metrics[0]", "has no attribute 'NoMetric'"),
    (['ego.layers=["toyplug:ToyLayr"]'], "ego.layers[0]", "has no attribute 'ToyLayr'"),
    (["controllers.toyy.gain=1"], "controllers.toyy", "no controller of that name"),
])
def test_bad_choice_or_table_is_one_line_naming_the_key(toy, overrides, key, says):
    with pytest.raises(ScenarioError) as err:
        scenario.load(SCENARIOS / "overtaking.toml", overrides)
    assert err.value.key == key and says in str(err.value) and "\n" not in str(err.value)
