"""Batches: run keys, seeds, bad input, the progress bar (the runs' child processes, crashes, SIGKILL +
resume and Ctrl-C: tests/runs/test_child_processes.py; Dask: test_dask.py)."""
import hashlib
import json
import pathlib
import shutil

import pytest
from conftest import OVERTAKING, SHORT, cli_in_process

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs import faults
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import batch

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_run_key_covers_scenario_net_routes_overrides_controller_seed(tmp_path):
    k = batch.plan(OVERTAKING, 1, SHORT).key
    assert batch.plan(OVERTAKING, 1, SHORT, "apf_sa").key == k  # the scenario's own controller
    assert len({k, batch.plan(OVERTAKING, 2, SHORT).key, batch.plan(OVERTAKING, 1, SHORT[:1]).key,
                batch.plan(OVERTAKING, 1, SHORT, "apf").key}) == 4
    for f in ("scenarios/overtaking.toml", "scenarios/overtaking.rou.xml", "nets/overtaking.net.xml"):
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / f, tmp_path / f)
    copy = tmp_path / "scenarios" / "overtaking.toml"
    assert batch.plan(copy, 1, SHORT).key == k  # content, not location
    rou = tmp_path / "scenarios" / "overtaking.rou.xml"
    rou.write_text(rou.read_text() + "\n<!-- changed -->\n")
    assert batch.plan(copy, 1, SHORT).key != k


def test_run_key_is_the_hash_the_ledgers_in_reports_are_keyed_by():
    """sha256 of the key version, the files' digests and the run's arguments with ``"inject_crash": None``
    (crash injection was once part of the key: keeping the field keeps every recorded key valid)."""
    scn = scenario.load(OVERTAKING, SHORT, seed=4)
    h = hashlib.sha256(b"sumo_avoid-run-key-v1")
    for f in (OVERTAKING, scn.net_file, *scn.route_files, *scn.additional_files):
        h.update(hashlib.sha256(pathlib.Path(f).read_bytes()).digest())
    h.update(json.dumps({"overrides": SHORT, "controller": "apf_sa", "seed": 4, "inject_crash": None},
                        sort_keys=True).encode())
    assert batch.plan(OVERTAKING, 4, SHORT).key == h.hexdigest()


def test_bad_input_is_one_line_and_writes_nothing(tmp_path, monkeypatch):
    db = tmp_path / "l.sqlite"
    for args, words in [(["--seeds", "5-1"], "--seeds"), (["--set", "sim.duration_s=-1"], "sim.duration_s"),
                        (["--workers", "0"], "--workers"), (["--controller", "nope"], "ego.controller"),
                        (["--start", "vfork"], "--start")]:
        r = cli_in_process("batch", OVERTAKING, "--ledger", db, *args, cwd=ROOT)
        assert r.returncode == 2, r.stderr
        assert r.stderr.count("\n") == 1 and words in r.stderr and r.stderr.startswith("sumo-avoid: error:")
    monkeypatch.setenv(faults.ENV, "meteor:1")  # test-only fault injection, malformed
    r = cli_in_process("batch", OVERTAKING, "--ledger", db, cwd=ROOT)
    assert r.returncode == 2 and faults.ENV in r.stderr and r.stderr.count("\n") == 1
    assert not db.exists()


@pytest.mark.parametrize("text,seeds", [("1-3", (1, 2, 3)), ("1,3,7", (1, 3, 7)), ("1-2,9", (1, 2, 9)),
                                        ([4, 2, 2], (2, 4)), (5, (5,))])
def test_parse_seeds(text, seeds):
    assert batch.parse_seeds(text) == seeds


def test_progress_is_quiet_in_ci_or_without_a_terminal(monkeypatch):
    monkeypatch.setenv("CI", "true")
    assert batch._Progress(5).bar is None
    monkeypatch.delenv("CI")
    assert batch._Progress(5).bar is None  # pytest captures stderr: not a terminal
    bar = batch._Progress(3, enabled=True)
    bar.update(True)
    bar.update(False)
    assert (bar.done, bar.failed, bar.bar.n) == (1, 1, 2)
    bar.close()


def test_an_ego_that_never_departs_is_named_before_the_batch_runs(tmp_path):
    """The same error as `sumo-avoid run`: an ego whose depart time is after the run's end is bad
    input, found from the route file when the batch is planned (nothing runs); the other grid point plans."""
    (tmp_path / "r.rou.xml").write_text('<routes>\n  <trip id="ego" from="road" to="road" depart="0"/>\n'
                                        '  <trip id="late" from="road" to="road" depart="60"/>\n</routes>\n')
    scn = tmp_path / "late.toml"
    scn.write_text(f'name = "late"\n[sim]\nnet = "{ROOT / "nets" / "overtaking.net.xml"}"\nroutes = ["r.rou.xml"]\n'
                   'duration_s = 3.0\n[ego]\nids = ["ego", "late"]\n[output]\nplots = false\n')
    with pytest.raises(ScenarioError) as err:
        batch.expand([scn], [1], grid={"ego.ids": [["ego", "late"], ["ego"]]})
    assert str(err.value) == (f"{scn}: key 'ego.ids[1]': expected egos that depart within the run: 'late' departs "
                              "at t=60 s, the run ends at sim.duration_s = 3 s")
    assert len(batch.expand([scn], [1], grid={"ego.ids": [["ego"]]})) == 1