"""``sumo-avoid reproduce table4`` end to end on a tiny flock (the real study is 100 vehicles x 600 s),
and an error raised inside its process pool reaching the parent as one line instead of a hang."""
from __future__ import annotations

import csv
import pickle

import pytest

from sumo_avoid.cli import main
from sumo_avoid.core.config import ScenarioError


@pytest.mark.sumo
def test_table4_runs_the_three_speeds_on_a_tiny_flock(tmp_path):
    out = tmp_path / "t4"
    assert main(["reproduce", "table4", "--seeds", "1", "--agents", "6", "--duration", "3", "--jobs", "1",
                 "--out", str(out)]) == 0
    rows = list(csv.DictReader((out / "table4.csv").open()))
    assert {r["v_flock"] for r in rows} == {"4", "6", "8"}
    assert sorted(p.name for p in (out / "runs").iterdir()) == ["v4_s1.json", "v6_s1.json", "v8_s1.json"]


def test_scenario_error_survives_pickling():
    e = ScenarioError("a.toml", "sim.step_s", "a number", "x")
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is ScenarioError and str(back) == str(e) == "a.toml: key 'sim.step_s': expected a number, got 'x'"
    quiet = pickle.loads(pickle.dumps(ScenarioError("a.toml", "sim", "files SUMO can load", show_got=False)))
    assert str(quiet) == "a.toml: key 'sim': expected files SUMO can load"


@pytest.mark.parametrize("flag", [False, True])
def test_reproduce_formation_passes_retry_failed_to_its_batch(tmp_path, monkeypatch, flag):
    from sumo_avoid.studies import batch

    seen = []

    def stop(cfg):
        seen.append(cfg)
        raise KeyboardInterrupt  # stop before anything runs

    monkeypatch.setattr(batch, "run_batch", stop)
    code = main(["reproduce", "formation", "--runs", "1", "--workers", "1", "--out", str(tmp_path / "f"),
                 *(["--retry-failed"] if flag else [])])
    assert code != 0  # interrupted (the CLI turns Ctrl-C into one line and a non-zero exit)
    assert len(seen) == 1 and seen[0].retry_failed is flag and len(seen[0].runs) > 0
