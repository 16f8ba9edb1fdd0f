"""Outputs that cannot be written (issue 35, part 3): ``run``, ``batch`` and ``suite`` on a full disk, a
read-only folder and a folder that vanishes mid-run each print one line naming the path and the OS's
reason, exit with code 2 and leave nothing half-written (a run's folder is removed; the ledger keeps
every row it had). Real libsumo runs on the overtaking scenario, each command in a process of its own
(disks.py: the mechanisms, skipped with the reason where one is not available)."""
from __future__ import annotations

import sqlite3

import pytest
from conftest import OVERTAKING, cli_in_process
from disks import cli, files_under, one_line, remove, tmpfs, when_made  # noqa: F401 (tmpfs: a fixture)

from sumo_avoid.studies import ledger

pytestmark = pytest.mark.sumo
NO_SPACE, TOO_LARGE = "No space left on device", "File too large"
READ_ONLY, GONE = "Read-only file system", "No such file or directory"
SHORT = ("--set", "sim.duration_s=3", "--set", "output.plots=false", "--quiet")
LONG = ("--set", "sim.duration_s=12", "--set", "output.plots=false", "--quiet")  # trajectories.csv ~75 kB
LIMIT = 64 * 1024  # above SQLite's 32 kB shared-memory file, below a 12 s run's trajectories


def test_run_on_a_full_disk_under_its_own_folder(tmp_path):
    out = tmp_path / "out"
    r = cli("run", OVERTAKING, *LONG, "--no-plots", "--out", out, cwd=tmp_path, fsize=LIMIT)
    one_line(r, "cannot write ", "trajectories.csv", TOO_LARGE)
    assert not out.exists() and r.stdout == ""


def test_run_whose_out_folder_fills_up(tmp_path, tmpfs):
    tmpfs.fill()
    out = tmpfs.path / "out"
    r = cli("run", OVERTAKING, *SHORT, "--no-plots", "--out", out, cwd=tmp_path)
    one_line(r, f"cannot write {out / 'metrics.json'}: {NO_SPACE}")
    assert files_under(tmpfs.path) == ["filler"] and not out.exists()


def test_run_whose_out_folder_turns_read_only(tmp_path, tmpfs):
    out = tmpfs.path / "out"
    r = cli("run", OVERTAKING, *SHORT, "--no-plots", "--out", out, cwd=tmp_path,
            during=when_made(out, tmpfs.read_only))
    one_line(r, f"cannot write {out / 'metrics.json'}: {READ_ONLY}")
    assert files_under(tmpfs.path) == []  # the folder stays (a read-only file system), empty


def test_run_whose_out_folder_vanishes(tmp_path):
    out = tmp_path / "gone" / "out"
    r = cli("run", OVERTAKING, *SHORT, "--no-plots", "--out", out, cwd=tmp_path,
            during=when_made(out, remove(tmp_path / "gone")))
    # gone while the run writes, or (on a busy machine) already before run checked --out: either way one line
    # naming the folder and why (a clean-clone run with the capped numpy dispatch lost the race the second way)
    line = one_line(r, out, GONE)
    assert f"cannot write {out / 'metrics.json'}: {GONE}" in line or "key '--out'" in line, line
    assert not (tmp_path / "gone").exists()


def _recorded(tmp_path, led, *sets):
    """A ledger holding seed 1's run (done), its rows' hashes and its files."""
    r = cli("batch", OVERTAKING, "--seeds", "1", *sets, "--ledger", led, "--workers", "1", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    return ledger.row_hashes(led), files_under(led.parent / "runs")


def test_batch_on_a_full_disk_keeps_every_recorded_row(tmp_path):
    led = tmp_path / "led" / "ledger.sqlite"
    rows, runs = _recorded(tmp_path, led, *LONG)
    r = cli("batch", OVERTAKING, "--seeds", "1-3", *LONG, "--ledger", led, "--workers", "1", cwd=tmp_path, fsize=LIMIT)
    one_line(r, "cannot write ", str(led.parent / "runs"), "trajectories.csv", TOO_LARGE)
    assert ledger.row_hashes(led) == rows  # seed 1 kept as it was, seeds 2 and 3 not recorded
    assert files_under(led.parent / "runs") == runs  # no folder of seed 2 or 3, nothing in runs/.tmp


def test_batch_whose_ledger_folder_fills_up(tmp_path, tmpfs):
    led = tmpfs.path / "ledger.sqlite"
    rows, runs = _recorded(tmp_path, led, *SHORT)
    tmpfs.fill()
    r = cli("batch", OVERTAKING, "--seeds", "1-2", *SHORT, "--ledger", led, "--workers", "1", cwd=tmp_path)
    one_line(r, f"cannot write {tmpfs.path / 'runs'}", NO_SPACE)
    assert ledger.row_hashes(led) == rows and files_under(tmpfs.path / "runs") == runs


def test_batch_whose_ledger_fills_up_mid_batch_keeps_the_rows_before(tmp_path, monkeypatch):
    """SQLite's own full disk, on the second row (a real one is a matter of page sizes and WAL frames)."""
    led, calls = tmp_path / "led" / "ledger.sqlite", []
    full = sqlite3.OperationalError("database or disk is full")

    def record(*a):
        calls.append(1)
        if len(calls) == 2:
            raise full
        return real(*a)
    real = ledger._record
    monkeypatch.setattr(ledger, "_record", record)
    r = cli_in_process("batch", OVERTAKING, "--seeds", "1-3", *SHORT, "--ledger", led, "--workers", "1", cwd=tmp_path)
    one_line(r, f"cannot write {led.absolute()}: database or disk is full")
    monkeypatch.undo()
    assert len(ledger.row_hashes(led)) == 1 and len(calls) == 2  # the first row kept, the third run never recorded
    assert {f.split("/")[0] for f in files_under(led.parent / "runs")} == {ledger.read(led)["key"][0][:16]}


def test_batch_whose_ledger_folder_is_read_only(tmp_path, tmpfs):
    led = tmpfs.path / "ledger.sqlite"
    rows, runs = _recorded(tmp_path, led, *SHORT)
    tmpfs.read_only()
    r = cli("batch", OVERTAKING, "--seeds", "1-2", *SHORT, "--ledger", led, cwd=tmp_path)
    one_line(r, str(led), READ_ONLY)
    assert ledger.row_hashes(led) == rows and files_under(tmpfs.path / "runs") == runs


def test_batch_whose_ledger_folder_vanishes(tmp_path):
    led = tmp_path / "gone" / "ledger.sqlite"
    r = cli("batch", OVERTAKING, "--seeds", "1-2", *SHORT, "--ledger", led, "--workers", "1", cwd=tmp_path,
            during=when_made(led, remove(tmp_path / "gone")))
    one_line(r, "cannot write ", str(tmp_path / "gone"), GONE)
    assert not (tmp_path / "gone").exists()  # not made again by a later run or the export


def _suite(tmp_path, duration_s: float):
    p = tmp_path / "s.suite.toml"
    p.write_text(f'[[entry]]\nname = "a"\nscenario = "{OVERTAKING}"\nseeds = "1"\ncriteria = ["collisions == 0"]\n'
                 f'set = ["sim.duration_s={duration_s}", "output.plots=false"]\n')
    return p


def test_suite_on_a_full_disk(tmp_path):
    junit = tmp_path / "j" / "suite.xml"
    r = cli("suite", _suite(tmp_path, 12), "--junit", junit, "--quiet", cwd=tmp_path, fsize=LIMIT)
    one_line(r, "cannot write ", "trajectories.csv", TOO_LARGE)
    assert not junit.parent.exists()


def test_suite_whose_junit_folder_is_read_only(tmp_path, tmpfs):
    tmpfs.read_only()
    junit = tmpfs.path / "suite.xml"
    r = cli("suite", _suite(tmp_path, 3), "--junit", junit, "--quiet", cwd=tmp_path)
    one_line(r, str(junit), READ_ONLY)
    assert r.stdout == ""  # refused before any run


def test_suite_whose_ledger_folder_vanishes(tmp_path):
    led = tmp_path / "gone" / "ledger.sqlite"
    r = cli("suite", _suite(tmp_path, 3), "--ledger", led, "--quiet", cwd=tmp_path,
            during=when_made(led, remove(tmp_path / "gone")))
    one_line(r, "cannot write ", str(tmp_path / "gone"), GONE)
    assert not (tmp_path / "gone").exists()


def test_run_into_a_folder_that_holds_a_finished_run_is_refused(tmp_path):
    """Nothing finished is rewritten: a second ``run --out`` into the first one's folder is refused before
    SUMO starts, one line naming the folder, exit 2, the first run's files byte for byte as they were."""
    out = tmp_path / "out"
    first = cli_in_process("run", OVERTAKING, *SHORT, "--no-plots", "--out", out)
    assert first.returncode == 0, first.stderr
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    r = cli_in_process("run", OVERTAKING, *SHORT, "--no-plots", "--seed", "2", "--out", out)
    one_line(r, "'--out'", str(out), "metrics.json")
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_run_whose_out_folder_has_a_folder_of_a_result_files_name(tmp_path):
    """A folder named metrics.json in ``--out``: the run's file was moved inside it and the run said it was done
    (exit 0). Now one line naming it, exit 2, nothing written beside it."""
    out = tmp_path / "out"
    (out / "metrics.json").mkdir(parents=True)
    r = cli_in_process("run", OVERTAKING, *SHORT, "--no-plots", "--out", out)
    one_line(r, f"cannot write {out / 'metrics.json'}: Is a directory")
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == ["metrics.json"]
