"""Outputs that cannot be written (issue 35, part 3): ``report``, ``reproduce`` and ``tune`` on a full
disk, a read-only folder and a folder that vanishes mid-run: one line naming the path and the OS's
reason, exit code 2, nothing half-written. Real libsumo runs (a one-run ledger for the report, Table 4
with 3 agents for 1 s, a formation tuning of 2 candidates), each command in a process of its own
(disks.py: the mechanisms, skipped with the reason where one is not available)."""
from __future__ import annotations

import pytest
from conftest import GAP, OVERTAKING
from disks import cli, files_under, one_line, remove, tmpfs, when_made  # noqa: F401 (tmpfs: a fixture)

pytestmark = pytest.mark.sumo
TOO_LARGE, READ_ONLY, GONE = "File too large", "Read-only file system", "No such file or directory"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """A ledger of one 3 s overtaking run with its plots (its report is ~200 kB of HTML)."""
    d = tmp_path_factory.mktemp("study")
    led = d / "ledger.sqlite"
    r = cli("batch", OVERTAKING, "--seeds", "1", "--set", "sim.duration_s=3", "--ledger", led, "--workers", "1",
            "--quiet", cwd=d)
    assert r.returncode == 0, r.stderr
    return led


def test_report_on_a_full_disk(tmp_path, study):
    out = tmp_path / "o" / "r.html"
    r = cli("report", study, "--out", out, cwd=tmp_path, fsize=64 * 1024)
    one_line(r, f"cannot write {out}: {TOO_LARGE}")
    assert not out.parent.exists()


def test_report_into_a_read_only_folder(tmp_path, tmpfs, study):
    tmpfs.read_only()
    r = cli("report", study, "--out", tmpfs.path / "r.html", cwd=tmp_path)
    one_line(r, "--out", str(tmpfs.path), READ_ONLY)


def test_report_whose_folder_vanishes(tmp_path, study):
    # report writes its page a moment after making the folder: on a busy machine it may win the race
    # with the remover, and then the attempt proves nothing and is made again (in a fresh folder)
    for attempt in range(8):
        out = tmp_path / f"gone{attempt}" / "r.html"
        r = cli("report", study, "--out", out, cwd=tmp_path, during=when_made(out.parent, remove(out.parent)))
        if r.returncode != 0 or out.exists():
            break
    # gone before report has checked its folder, or while it writes: either way one line naming it and why
    line = one_line(r, out.parent, GONE)
    assert f"cannot write {out}: {GONE}" in line or "key '--out'" in line, line
    assert not out.parent.exists()


TABLE4 = ("reproduce", "table4", "--seeds", "1", "--agents", "3", "--duration", "1", "--jobs", "1")


def test_reproduce_on_a_full_disk(tmp_path):
    out = tmp_path / "t4"
    r = cli(*TABLE4, "--out", out, cwd=tmp_path, fsize=12_000)  # below a figure (~17 kB), above the rest
    one_line(r, f"cannot write {out}/fig7_v", TOO_LARGE)
    assert not out.exists()  # no half-written figure, no table, no empty folders


def test_reproduce_into_a_read_only_folder(tmp_path, tmpfs):
    tmpfs.read_only()
    r = cli(*TABLE4, "--out", tmpfs.path, cwd=tmp_path)
    one_line(r, "--out", str(tmpfs.path), READ_ONLY)


def test_reproduce_whose_folder_vanishes(tmp_path):
    out = tmp_path / "gone" / "t4"
    r = cli(*TABLE4, "--out", out, cwd=tmp_path, during=when_made(out, remove(tmp_path / "gone")))
    # removed while it writes ("cannot write ...") or already between --out's check making the folder and testing it
    # (the --out key's line): one line naming the folder and the reason either way
    one_line(r, str(out), GONE)
    assert not (tmp_path / "gone").exists()


TUNE = ("tune", "formation", GAP, "--generations", "0", "--nests", "2", "--seeds", "1", "--workers", "1", "--quiet")


def test_tune_on_a_full_disk(tmp_path):
    out = tmp_path / "tune"
    r = cli(*TUNE, "--set", "sim.duration_s=20", "--out", out, cwd=tmp_path, fsize=48 * 1024)  # a run's ~73 kB
    one_line(r, f"cannot write {out / 'runs'}", "trajectories.csv", TOO_LARGE)
    assert [f for f in files_under(out) if not f.startswith("ledger.sqlite")] == []  # the (empty) ledger only


def test_tune_into_a_read_only_folder(tmp_path, tmpfs):
    tmpfs.read_only()
    r = cli(*TUNE, "--set", "sim.duration_s=1", "--out", tmpfs.path / "tune", cwd=tmp_path)
    one_line(r, "--out", str(tmpfs.path), READ_ONLY)


def test_tune_whose_folder_vanishes(tmp_path):
    out = tmp_path / "gone"
    r = cli(*TUNE, "--set", "sim.duration_s=1", "--out", out, cwd=tmp_path,
            during=when_made(out / "ledger.sqlite", remove(out)))
    one_line(r, f"cannot write {out}", GONE)
    assert not out.exists()


def test_report_of_a_ledger_in_a_read_only_folder_draws_its_plots_elsewhere(tmp_path, tmpfs):
    """Runs without plots: the report draws them, into the run's folder where it can (kept), else elsewhere."""
    led = tmpfs.path / "ledger.sqlite"
    r = cli("batch", OVERTAKING, "--seeds", "1", "--set", "sim.duration_s=3", "--set", "output.plots=false",
            "--ledger", led, "--workers", "1", "--quiet", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    tmpfs.read_only()
    before = files_under(tmpfs.path)
    r = cli("report", led, "--out", tmp_path / "r.html", cwd=tmp_path)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    page = (tmp_path / "r.html").read_text()
    assert '<img alt="trajectory overtaking' in page and '<img alt="time series"' in page
    assert files_under(tmpfs.path) == before and "trajectory.png" not in " ".join(before)
