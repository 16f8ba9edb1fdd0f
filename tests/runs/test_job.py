"""RunJob and RunOutcome cross process boundaries as JSON: every field comes back equal and of its
type; test-only fault injection is read from the environment, outside the job."""
import json
import math

import pytest

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs import faults
from sumo_avoid.runs.job import SCENARIO, STATUSES, RunJob, RunOutcome


def _through_json(d: dict) -> dict:
    return json.loads(json.dumps(d))  # as it travels: a pipe line, an argument, result.json


def test_a_job_with_every_field_set_round_trips():
    job = RunJob("/abs/s.toml", 7, ("sim.duration_s=5", "output.plots=false"), "apf", plots=False, key="ab" * 32,
                 kind="sumo_avoid.studies.reproduce:flocking_record", params={"v": 4, "figure": None, "sets": ["a=1"]},
                 out_dir="/tmp/x", progress=True)
    back = RunJob.from_json(_through_json(job.to_json()))
    assert back == job
    assert isinstance(back.overrides, tuple)


def test_a_default_job_round_trips_and_is_the_standard_kind():
    job = RunJob("/abs/s.toml")
    assert (job.seed, job.controller, job.kind, job.plots, job.progress) == (None, None, SCENARIO, True, False)
    assert RunJob.from_json(_through_json(job.to_json())) == job


@pytest.mark.parametrize("outcome", [
    RunOutcome("done", metrics={"collisions": 0, "min_gap_m": 1.5, "collision_events": [[1, 0.1, "a", "b", 0.0, 1.0]],
                                "time_to_goal_s": None}, timings_s={"setup_s": 0.2, "loop_s": 1.0, "total_s": 1.2},
               cpu_s=1.1, clock_s={"dispatch_wall": 1e9, "sumo_start_wall": 1e9 + 0.5}, overhead_s=0.5,
               started_at="2026-11-27T05:00:00.000+00:00", ended_at="2026-11-27T05:00:02.000+00:00", wall_s=2.0,
               start="fork", artifacts="/tmp/runs/abcd"),
    RunOutcome("failed", error="ScenarioError: s.toml: key 'ego.ids[0]': expected ...", bad_input="s.toml: ..."),
    RunOutcome("crashed", error="worker died: SIGSEGV (segmentation fault)", where="libsumo/libsumo.py:3545 (start)"),
    RunOutcome("timeout", error="timeout: run exceeded 0.3 s and was killed", wall_s=0.31, start="spawn"),
])
def test_an_outcome_round_trips(outcome):
    assert RunOutcome.from_json(_through_json(outcome.to_json())) == outcome


def test_an_outcome_keeps_nan_and_infinity_metrics():
    back = RunOutcome.from_json(_through_json(RunOutcome("done", metrics={"a": math.nan, "b": math.inf}).to_json()))
    assert math.isnan(back.metrics["a"]) and back.metrics["b"] == math.inf


def test_every_way_to_fail_is_failed_in_the_ledger():
    assert [RunOutcome(s).ledger_status for s in STATUSES] == ["done", "failed", "failed", "failed"]
    assert [RunOutcome(s).ok for s in STATUSES] == [True, False, False, False]
    with pytest.raises(ValueError, match="status must be one of"):
        RunOutcome("finished")


def test_fault_injection_targets_a_seed_a_key_prefix_or_every_run():
    job = RunJob("/abs/s.toml", 102, key="3f2a9c01" + "0" * 56)
    assert faults.crash_for(job, "") is None
    assert faults.crash_for(job, "abort:102") == "abort"
    assert faults.crash_for(job, "abort:101") is None
    assert faults.crash_for(job, "segfault:3f2a9c") == "segfault"
    assert faults.crash_for(job, "segfault:3f2b") is None
    assert faults.crash_for(job, "abort:1, segfault_mid_run:*") == "segfault_mid_run"
    assert faults.crash_for(RunJob("/abs/s.toml"), "abort:102") is None  # the scenario's own seed: not a target


def test_fault_injection_is_read_from_the_environment_and_a_bad_value_is_one_line(monkeypatch):
    job = RunJob("/abs/s.toml", 5)
    monkeypatch.setenv(faults.ENV, "abort:5")
    assert faults.crash_for(job) == "abort"
    assert "abort" not in json.dumps(job.to_json())  # never part of the job
    for bad in ("meteor:5", "abort", "abort:", "segfault 5"):
        monkeypatch.setenv(faults.ENV, bad)
        with pytest.raises(ScenarioError) as err:
            faults.crash_for(job)
        assert str(err.value).startswith(f"<environment>: key '{faults.ENV}': expected KIND:TARGET")
        assert "\n" not in str(err.value)


def test_a_job_kind_is_the_standard_run_or_a_module_function():
    assert RunJob("/abs/s.toml", kind="sumo_avoid.studies.table4:flocking_record").kind.endswith(":flocking_record")
    for bad in ("table4", "sumo_avoid.studies.table4:", ":f", "m:f g"):
        with pytest.raises(ValueError, match="RunJob.kind must be"):
            RunJob("/abs/s.toml", kind=bad)
