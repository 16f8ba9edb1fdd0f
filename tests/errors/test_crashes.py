"""SUMO crashing under `run` and `batch` (issue 17 item 2), and a batch mixing good and bad inputs.

`run` simulates in a process of its own (the batch's worker), so a SIGSEGV inside SUMO, at load or
mid-run, becomes one line and exit code 3; the output folder gets SUMO's log and a failure record,
never a metrics.json. Short runs (2-3 s simulated, no plots)."""
from __future__ import annotations

import json
import sqlite3
import tempfile

import pytest
from conftest import ROOT, cli_in_process

from sumo_avoid.runs import faults

pytestmark = pytest.mark.sumo
SCN = ROOT / "scenarios" / "overtaking.toml"
SEGFAULT_NET = ROOT / "tests" / "data" / "segfault_net.toml"  # a real net that segfaults SUMO 1.28 on load
SHORT = ("--set", "sim.duration_s=3.0", "--quiet", "--no-plots")


def _crashed(r, out):
    assert r.returncode == 3, r.stderr
    line, = r.stderr.strip().splitlines()
    assert line.startswith("sumo-avoid: error: ") and "SIGSEGV" in line and str(out / "sumo.log") in line, line
    assert sorted(p.name for p in out.iterdir()) == ["failed.json", "sumo.log"]
    rec = json.loads((out / "failed.json").read_text())
    assert rec["status"] == "failed" and "SIGSEGV" in rec["error"]
    return line


def test_run_on_a_net_that_segfaults_sumo_exits_3_in_one_line(tmp_path):
    out = tmp_path / "out"
    r = cli_in_process("run", SEGFAULT_NET, "--out", out, *SHORT)
    line = _crashed(r, out)
    assert str(SEGFAULT_NET) in line


def test_run_segfault_mid_run_exits_3_and_the_log_is_kept(tmp_path, monkeypatch):
    out = tmp_path / "out"
    monkeypatch.setenv(faults.ENV, "segfault_mid_run:*")  # test-only fault injection
    r = cli_in_process("run", SCN, "--out", out, *SHORT)
    _crashed(r, out)
    assert "Simulation" in (out / "sumo.log").read_text() or (out / "sumo.log").stat().st_size >= 0


def test_a_run_killed_mid_run_leaves_no_temporary_files(tmp_path, monkeypatch):
    """The run's SSM output and rewritten files live in a folder the parent removes after the child: a child
    killed by SIGSEGV (or a timeout) left its ``sumo-avoid-run-*`` folder in the system's temp folder for good."""
    sys_tmp = tmp_path / "sys_tmp"
    sys_tmp.mkdir()
    monkeypatch.setenv("TMPDIR", str(sys_tmp))
    monkeypatch.setattr(tempfile, "tempdir", str(sys_tmp))
    monkeypatch.setenv(faults.ENV, "segfault_mid_run:*")  # test-only fault injection
    r = cli_in_process("run", SCN, "--out", tmp_path / "out", *SHORT)
    _crashed(r, tmp_path / "out")
    assert list(sys_tmp.iterdir()) == []


def _batch(tmp_path, runs: str):
    p = tmp_path / "b.toml"
    p.write_text(f'ledger = "led/ledger.sqlite"\ntimeout_s = 120.0\n{runs}')
    return p


def _run(scenario, seeds="1"):
    return f'[[runs]]\nscenario = "{scenario}"\nseeds = "{seeds}"\nset = ["sim.duration_s=3.0", "output.plots=false"]\n'


def test_batch_records_a_segfault_mid_run_as_failed(tmp_path, monkeypatch):
    p = _batch(tmp_path, _run(SCN, "1-2"))
    monkeypatch.setenv(faults.ENV, "segfault_mid_run:2")  # test-only fault injection: seed 2 crashes
    r = cli_in_process("batch", p, "--quiet", "--workers", "2")
    assert r.returncode == 1, r.stderr
    with sqlite3.connect(tmp_path / "led" / "ledger.sqlite") as con:
        rows = sorted(con.execute("SELECT status, error FROM runs"), key=lambda x: x[0])
    assert rows[0] == ("done", None) and rows[1] == ("failed", "worker died: SIGSEGV (segmentation fault)")


def _mixed(tmp_path):
    (tmp_path / "junk.toml").write_bytes(b'name = "junk\n\x00\xff')
    (tmp_path / "nonet.toml").write_text(SCN.read_text().replace("../nets/overtaking.net.xml", "gone.net.xml")
                                         .replace('"overtaking.rou.xml"', f'"{ROOT / "scenarios" / "overtaking.rou.xml"}"'))
    return [SCN, tmp_path / "junk.toml", tmp_path / "nonet.toml", SEGFAULT_NET]


def test_a_batch_names_every_bad_input_before_it_runs(tmp_path):
    led = tmp_path / "led" / "ledger.sqlite"
    r = cli_in_process("batch", *_mixed(tmp_path), "--ledger", led, *SHORT[:2])
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 2 and all(ln.startswith("sumo-avoid: error: ") for ln in lines), lines
    assert "junk.toml: key '<syntax>'" in lines[0] and "nonet.toml: key 'sim.net'" in lines[1]
    assert not led.parent.exists() and r.stdout == ""


def test_a_batch_with_keep_going_runs_the_good_and_records_each_bad_with_its_cause(tmp_path):
    led = tmp_path / "led" / "ledger.sqlite"
    r = cli_in_process("batch", *_mixed(tmp_path), "--ledger", led, *SHORT[:3], "--set", "output.plots=false", "--keep-going", "--workers", "2")
    assert r.returncode == 1, r.stderr
    with sqlite3.connect(led) as con:
        rows = {path.rsplit("/", 1)[-1]: (status, error) for path, status, error
                in con.execute("SELECT scenario_path, status, error FROM runs")}
    assert rows["overtaking.toml"] == ("done", None)
    assert rows["junk.toml"][0] == "failed" and rows["junk.toml"][1].startswith("bad input: ") and "<syntax>" in rows["junk.toml"][1]
    assert rows["nonet.toml"][0] == "failed" and "'sim.net'" in rows["nonet.toml"][1]
    assert rows["segfault_net.toml"] == ("failed", "worker died: SIGSEGV (segmentation fault)")
