"""Scenario suites: the criteria language (parsed, never eval'd), exit codes and JUnit XML."""
import pathlib
import xml.etree.ElementTree as ET

import pytest

from sumo_avoid.cli import main
from sumo_avoid.core.config import ScenarioError
from sumo_avoid.studies.suite import Criterion

ROOT = pathlib.Path(__file__).resolve().parents[2]
OVERTAKING = ROOT / "scenarios" / "overtaking.toml"


@pytest.mark.parametrize("text,metric,op,value", [("collisions == 0", "collisions", "==", 0.0),
                                                  ("goal_reached_rate>=0.9", "goal_reached_rate", ">=", 0.9),
                                                  (" phi_wall <= 1e-1 ", "phi_wall", "<=", 0.1),
                                                  ("goal_reached == true", "goal_reached", "==", 1.0)])
def test_criterion_parses(text, metric, op, value):
    c = Criterion.parse(text)
    assert (c.metric, c.op, c.value) == (metric, op, value)


@pytest.mark.parametrize("text", ["__import__('os').system('x') == 0", "collisions = 0", "collisions == 0 or 1",
                                  "1 == collisions", "collisions == abc", "", 3])
def test_criterion_rejects_anything_else(text):
    with pytest.raises(ScenarioError, match="expected a criterion"):
        Criterion.parse(text, "s.toml", "entry[0].criteria[0]")


def test_criterion_semantics():
    rows = [{"seed": 1, "collisions": 0, "goal_reached": 1, "min_gap_m": 2.0},
            {"seed": 2, "collisions": 1, "goal_reached": 0, "min_gap_m": None}]
    assert Criterion.parse("collisions == 0").check(rows) == (False, "fails on 1/2 seeds (seed 2: 1)")
    assert Criterion.parse("collisions <= 1").check(rows)[0]
    assert Criterion.parse("goal_reached_rate >= 0.5").check(rows) == (True, "goal_reached rate = 0.5 over 2 seeds")
    assert not Criterion.parse("goal_reached_rate >= 0.9").check(rows)[0]
    assert Criterion.parse("collisions_max < 2").check(rows)[0]
    assert Criterion.parse("collisions_mean == 0.5").check(rows)[0]
    assert Criterion.parse("min_gap_m >= 0").check(rows) == (False, "fails on 1/2 seeds (seed 2: n/a)")
    assert Criterion.parse("mu >= 0.7").check(rows) == (False, "no metric 'mu'")
    assert Criterion.parse("collisions == 0").check([]) == (False, "no finished runs")


def _suite(path: pathlib.Path, failing: bool) -> pathlib.Path:
    text = f"""
[defaults]
seeds = "1-2"
set = ["sim.duration_s=5", "output.plots=false"]

[[entry]]
name = "overtaking-safe"
scenario = "{OVERTAKING}"
controller = "apf_sa"
criteria = ["collisions == 0", "phi_wall <= 0.1", "min_gap_m_min >= 0.5"]
"""
    if failing:  # the same runs, a criterion they cannot meet in 5 s
        text += f"""
[[entry]]
name = "overtaking-goal-in-5s"
scenario = "{OVERTAKING}"
controller = "apf_sa"
criteria = ["collisions == 0", "goal_reached_rate >= 0.9"]
"""
    path.write_text(text)
    return path


def test_suite_exit_codes_and_junit(tmp_path, capsys):
    led = tmp_path / "ledger.sqlite"
    junit = tmp_path / "junit.xml"
    rc = main(["suite", str(_suite(tmp_path / "bad.toml", True)), "--junit", str(junit), "--ledger", str(led),
               "--workers", "2", "--quiet"])
    out = capsys.readouterr().out
    assert rc == 1
    assert "1 of 2 entries passed, 1 FAILED" in out and "goal_reached rate = 0 over 2 seeds" in out
    suite = ET.parse(junit).getroot().find("testsuite")
    assert suite.get("tests") == "2" and suite.get("failures") == "1"
    cases = {c.get("name"): c for c in suite.findall("testcase")}
    assert cases["overtaking-safe"].find("failure") is None
    failure = cases["overtaking-goal-in-5s"].find("failure")
    assert failure is not None and "goal_reached_rate >= 0.9" in failure.get("message")
    # one click from the picture: the failure names its runs and their viewer pages beside the XML
    viewers = sorted((tmp_path / "junit_viewers").glob("overtaking-goal-in-5s-s*.html"))
    assert len(viewers) == 2 and f"viewer {viewers[0]}" in failure.get("message")
    assert all(f"viewer {v}" in failure.text for v in viewers) and "window.RUN=" in viewers[0].read_text()

    # the passing suite reuses the same runs from the ledger
    rc = main(["suite", str(_suite(tmp_path / "good.toml", False)), "--junit", str(junit), "--ledger", str(led),
               "--quiet"])
    out = capsys.readouterr().out
    assert rc == 0 and "1 of 1 entries passed" in out and "2 of 2 runs already recorded" in out
    assert ET.parse(junit).getroot().find("testsuite").get("failures") == "0"


def test_bad_suite_is_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "s.toml"
    bad.write_text(f'[[entry]]\nname = "x"\nscenario = "{OVERTAKING}"\nseeds = "1"\n'
                   'criteria = ["open(\\"f\\") == 1"]\n')
    assert main(["suite", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "entry[0].criteria[0]" in err


def test_project_suite_file_is_valid():
    from sumo_avoid.studies import suite

    entries = suite.load(ROOT / "scenarios" / "suite.toml")
    assert len(entries) >= 2 and all(e.criteria for e in entries)


@pytest.mark.parametrize("name", ["suite", "roads", "generated"])
def test_project_suites_name_only_metrics_their_runs_write(name):
    from sumo_avoid.studies import suite

    path = ROOT / "scenarios" / f"{name}.toml"
    suite.check_criteria(suite.load(path), str(path))  # raises on a criterion no run of its entry could meet


def test_criteria_are_checked_against_each_entrys_own_runs(tmp_path):
    """The flocking metric's mu exists only where the entry adds that metric (output.metrics); the
    check names the entry and the criterion, before anything runs."""
    from sumo_avoid.studies import suite

    path = tmp_path / "s.toml"
    entry = (f'[[entry]]\nname = "{{n}}"\nscenario = "{OVERTAKING}"\nseeds = "1"\ncriteria = ["mu_mean >= 0"]\n'
             'set = [{set}]\n')
    path.write_text(entry.format(n="with", set="'output.metrics=[\"flocking\"]'") + entry.format(n="without", set=""))
    with pytest.raises(ScenarioError) as e:
        suite.check_criteria(suite.load(path), str(path))
    assert e.value.key == "entry[1].criteria[0]" and e.value.got == "mu_mean"  # entry[0] passed
    assert "a run of this entry writes" in str(e.value) and "nearest: " in str(e.value)


def test_project_suite_quick_version_passes(tmp_path, capsys):
    """CI's quick run of scenarios/suite.toml: one seed per entry, full-length runs."""
    junit = tmp_path / "suite.xml"
    rc = main(["suite", str(ROOT / "scenarios" / "suite.toml"), "--seeds", "1", "--workers", "2",
               "--junit", str(junit), "--quiet"])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert ET.parse(junit).getroot().find("testsuite").get("failures") == "0"
