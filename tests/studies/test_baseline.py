"""``travel_time_ratio``: a run's time to goal against SUMO's own driver (controller ``sumo``) on the
same scenario and seed, from a real batch ledger (real runs) and in the report and the suite; empty
(NaN) where there is no baseline or no time."""
from __future__ import annotations

import json
import math

import pandas as pd
import pytest
from conftest import SCENARIOS

from sumo_avoid.cli import main
from sumo_avoid.studies import batch, ledger
from sumo_avoid.studies.baseline import with_travel_time_ratio

LEFT_TURN = SCENARIOS / "left_turn.toml"
QUIET = ["output.plots=false"]


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """left_turn: APF-SA on seeds 1 and 2, SUMO's driver on seed 1 only."""
    tmp = tmp_path_factory.mktemp("baseline")
    specs = batch.expand([LEFT_TURN], [1, 2], QUIET, ["apf_sa"]) + batch.expand([LEFT_TURN], [1], QUIET, ["sumo"])
    assert batch.run_batch(batch.BatchConfig(tuple(specs), tmp / "ledger.sqlite", workers=1), progress=False)["done"] == 3
    return tmp


def test_ratio_is_the_runs_time_over_the_baselines_time_read_from_the_ledger(study):
    df = with_travel_time_ratio(ledger.read(study / "ledger.sqlite"))
    row = {(r["controller"], r["seed"]): r for r in df.to_dict(orient="records")}
    apf, sumo = row[("apf_sa", 1)], row[("sumo", 1)]
    assert apf["goal_reached"] == 1 and sumo["goal_reached"] == 1
    assert apf["time_to_goal_s"] != sumo["time_to_goal_s"]  # two different drivers
    assert apf["travel_time_ratio"] == pytest.approx(apf["time_to_goal_s"] / sumo["time_to_goal_s"], rel=1e-12)
    assert sumo["travel_time_ratio"] == 1.0
    assert math.isnan(row[("apf_sa", 2)]["travel_time_ratio"])  # no baseline of seed 2 in the ledger


def test_report_shows_the_ratio_per_run_and_its_median(study, tmp_path):
    out, csv, md = tmp_path / "r.html", tmp_path / "runs.csv", tmp_path / "s.md"
    assert main(["report", str(study / "ledger.sqlite"), "--out", str(out), "--csv", str(csv), "--md", str(md)]) == 0
    runs = pd.read_csv(csv)
    ratio = dict(zip(zip(runs["controller"], runs["seed"]), runs["travel_time_ratio"]))
    assert ratio[("sumo", 1)] == 1.0 and math.isnan(ratio[("apf_sa", 2)]) and ratio[("apf_sa", 1)] > 0
    assert "travel_time_ratio_median" in md.read_text() and "<th>travel_time_ratio</th>" in out.read_text()


def test_suite_criterion_on_the_ratio_runs_the_baseline_itself(study, tmp_path, capsys):
    """The entry names only APF-SA; its ratio's baseline runs (seed 1) are added by the suite, and the
    ratio must be there for the criterion to pass."""
    led = tmp_path / "ledger.sqlite"
    suite = tmp_path / "s.toml"
    suite.write_text(f'[[entry]]\nname = "left"\nscenario = "{LEFT_TURN}"\ncontroller = "apf_sa"\nseeds = "1"\n'
                     f'set = {json.dumps(QUIET)}\ncriteria = ["travel_time_ratio_median <= 5", "travel_time_ratio > 0"]\n')
    assert main(["suite", str(suite), "--ledger", str(led), "--workers", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "2 runs (1 of them baselines for travel_time_ratio, controller sumo)" in out
    assert "travel_time_ratio median = " in out and "1 of 1 entries passed" in out
    assert sorted(ledger.read(led)["controller"]) == ["apf_sa", "sumo"]


def _rows(*rows):
    cols = ["key", "scenario", "scenario_path", "controller", "seed", "overrides", "status", "time_to_goal_s"]
    return pd.DataFrame([dict(zip(cols, r)) for r in rows])


def test_ratio_is_empty_without_a_baseline_time_and_matches_only_what_changes_sumos_run():
    same = json.dumps(['ego.sensor="radar"', "controllers.apf_sa.k_rep=100.0", "output.plots=false"])
    longer = json.dumps(["sim.duration_s=300"])
    df = with_travel_time_ratio(_rows(
        ("a", "s", "/s.toml", "apf_sa", 1, same, "done", 30.0),
        ("b", "s", "/s.toml", "sumo", 1, "[]", "done", 20.0),           # baseline of a: 1.5
        ("c", "s", "/s.toml", "apf_sa", 2, "[]", "done", 30.0),
        ("d", "s", "/s.toml", "sumo", 2, "[]", "done", None),           # baseline that never arrived
        ("e", "s", "/s.toml", "apf_sa", 1, longer, "done", 30.0),       # another setting: no baseline
        ("f", "s", "/s.toml", "apf_sa", 3, "[]", "done", None),         # did not arrive itself
        ("g", "s", "/s.toml", "sumo", 3, "[]", "done", 10.0),
        ("h", "s", "/other.toml", "apf_sa", 1, "[]", "done", 30.0),     # another scenario file
        ("i", "s", "/s.toml", "apf_sa", 1, "[]", "failed", None),
        ("j", "s", "/s.toml", "sumo", 4, "[]", "failed", None),         # a failed baseline is none
        ("k", "s", "/s.toml", "apf_sa", 4, "[]", "done", 12.0),
    ))
    got = dict(zip(df["key"], df["travel_time_ratio"]))
    assert got["a"] == 1.5 and got["b"] == 1.0 and got["g"] == 1.0
    assert all(math.isnan(got[k]) for k in "cdefhijk")
    assert with_travel_time_ratio(_rows())["travel_time_ratio"].empty
