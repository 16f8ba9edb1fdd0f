"""The metrics.json keys every metric and plug-in declares (``Keys``) against what real runs write:
short runs of real scenarios on real SUMO, together covering every controller, both layers (the
danger-time layer enforcing and as a radar's monitor), the flocking and formation metrics, an
arena and ``output.metrics``. A declaration that drifts from the code fails here, and with it the
suite's check of criteria before the runs (sumo_avoid/studies/suite.py)."""
from __future__ import annotations

import pytest
from conftest import run_scenario

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics import METRICS, STANDARD
from sumo_avoid.metrics.base import Metric
from sumo_avoid.runs.declared import metric_keys
from sumo_avoid.studies import report

RUNS = {  # scenario, overrides, controller: every controller, layer and extra metric at least once
    "apf_sa+rules+flocking_metric": ("overtaking", ["sim.duration_s=3", 'output.metrics=["flocking"]'], None),
    "apf+radar_monitor": ("overtaking", ["sim.duration_s=2", 'ego.layers=[]', 'ego.sensor="radar"'], "apf"),
    "scripted+danger_time": ("radar_brake", ["sim.duration_s=3"], None),
    "flocking_arena": ("arena_v4", ["sim.duration_s=2", "arena.n_agents=8"], None),
    "formation": ("formation/gap", ["sim.duration_s=2"], None),
    "ga_planner": ("planner/field", ["sim.duration_s=2"], None),
    "policy": ("overtaking", ["sim.duration_s=2", 'controllers.policy.policy="sumo_avoid.control.policy_examples:KeepLane"'],
               "policy"),
    "sumo_driver+radar": ("overtaking", ["sim.duration_s=3", 'ego.sensor="radar"'], "sumo"),  # no layer, no monitor
}


def kinds(metrics: dict) -> dict[str, str]:
    """Each key of a metrics.json dict and the kind of its value (None: either scalar kind)."""
    def kind(v):
        if v is None:
            return None
        if isinstance(v, (list, dict)):
            return "nested"
        return "text" if isinstance(v, str) else "numeric"
    return {k: kind(v) for k, v in metrics.items()}


@pytest.mark.parametrize("name", sorted(RUNS))
def test_declared_keys_are_exactly_the_keys_a_real_run_writes(name):
    scenario, overrides, controller = RUNS[name]
    res, m = run_scenario(scenario, overrides=overrides, controller=controller)
    declared = metric_keys(res.scenario)
    assert set(m) == declared.names, (sorted(set(m) - declared.names), sorted(declared.names - set(m)))
    of = {**dict.fromkeys(declared.numeric, "numeric"), **dict.fromkeys(declared.nested, "nested"),
          **dict.fromkeys(declared.text, "text")}
    wrong = {k: (of[k], got) for k, got in kinds(m).items() if got is not None and got != of[k]}
    assert not wrong
    assert len(of) == len(declared.numeric) + len(declared.nested) + len(declared.text)  # each key one kind


def test_keys_union_keeps_order_and_the_later_kind():
    a = Keys(("x", "y"), nested=("z",), text=("t",))
    b = Keys(("z", "w"), text=("y",))
    assert a | b == Keys(("x", "z", "w"), text=("y", "t"))
    assert (a | b).names == {"x", "y", "z", "w", "t"}
    assert Keys() | a == a and a | Keys() == a


def test_a_metric_without_a_declaration_is_refused_at_class_definition():
    with pytest.raises(TypeError, match="Loud declares no keys"):
        class Loud(Metric):
            def compute(self, run):
                return {"noise_db": 90.0}


def test_every_registered_metric_declares_each_key_once():
    for name in METRICS.names():
        k = METRICS[name].factory.keys
        listed = k.numeric + k.nested + k.text
        assert len(listed) == len(set(listed)), name


def test_the_report_columns_are_numbers_the_standard_metrics_declare():
    standard = Keys()
    for name in STANDARD:
        standard = standard | METRICS[name].factory.keys
    assert set(report.METRICS) <= set(standard.numeric)
