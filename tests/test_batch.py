"""Batches on real libsumo: crash isolation, SIGKILL + resume, Dask == local pool, bad input.

Runs are short (5 s of simulated time, no plots) to keep the whole file around a minute.
"""
import contextlib
import os
import pathlib
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from sumo_avoid import batch, ledger
from sumo_avoid.cli import main
from sumo_avoid.worker import run_one

ROOT = pathlib.Path(__file__).resolve().parents[1]
OVERTAKING = ROOT / "scenarios" / "overtaking.toml"
SHORT = ["sim.duration_s=5", "output.plots=false"]
METRIC_COLS = ["collisions", "min_gap_m", "phi_coll", "phi_wall", "mean_speed_mps", "path_length_m", "steps",
               "sumo_collisions", "goal_reached"]


def _cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "sumo_avoid.cli", *map(str, args)], capture_output=True,
                          text=True, cwd=ROOT, env={**os.environ, "CI": "true"}, **kw)


def _batch_file(tmp_path, seeds="1-20") -> pathlib.Path:
    f = tmp_path / "batch.toml"
    f.write_text(f"""
workers = 2
timeout_s = 120
ledger = "out/ledger.sqlite"

[[runs]]
scenario = "{OVERTAKING}"
seeds = "{seeds}"
controllers = ["apf_sa", "apf"]
set = {SHORT!r}

[[runs]]   # test-only fault injection: a real SIGSEGV (NULL dereference) in the worker
scenario = "{OVERTAKING}"
seeds = [101]
set = {SHORT!r}
inject_crash = "segfault"

[[runs]]   # test-only fault injection: os.abort() in the worker
scenario = "{OVERTAKING}"
seeds = [102]
set = {SHORT!r}
inject_crash = "abort"
""".replace("'", '"'))
    return f


def _alive_workers(marker: str) -> list[int]:
    pids = []
    for p in pathlib.Path("/proc").iterdir():
        try:
            cmd = (p / "cmdline").read_bytes().decode(errors="replace")
        except OSError:
            continue
        if p.name.isdigit() and "sumo_avoid.worker" in cmd and marker in cmd:
            pids.append(int(p.name))
    return pids


def _kill_midway(proc, db) -> dict:
    """SIGKILL the batch once 12 runs are recorded; return the row hashes at that moment."""
    deadline = time.time() + 120
    n = 0
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.3)
        if db.is_file():
            with contextlib.closing(sqlite3.connect(db)) as con:
                try:
                    n = con.execute("SELECT count(*) FROM runs").fetchone()[0]
                except sqlite3.OperationalError:  # the table is being created
                    continue
            if n >= 12:
                break
    assert proc.poll() is None, "batch finished before it could be killed"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    time.sleep(1.0)
    assert _alive_workers(str(db.parent)) == []  # PDEATHSIG: no orphaned runs keep going
    before = ledger.row_hashes(db)
    return before


def test_crashes_cost_only_their_run_and_sigkilled_batch_resumes(tmp_path):
    bf = _batch_file(tmp_path)
    specs, opts = batch.load_batch_file(bf)
    assert len(specs) == 42
    db = opts["ledger"]
    proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.cli", "batch", str(bf)], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env={**os.environ, "CI": "true"})
    try:
        before = _kill_midway(proc, db)
    finally:
        proc.kill()
    assert 12 <= len(before) < 42

    r = _cli("batch", bf)
    assert r.returncode == 1, r.stderr  # 1: the batch has failed runs
    assert f"{len(before)} of 42 runs already recorded" in r.stdout
    df = ledger.read(db)
    assert sorted(df["key"]) == sorted(s.key for s in specs)  # every run exactly once
    after = ledger.row_hashes(db)
    assert all(after[k] == h for k, h in before.items())  # nothing finished was rewritten
    failed = df[df["status"] == "failed"].set_index("seed")
    assert sorted(failed.index) == [101, 102]
    assert failed.loc[101, "error"] == "worker died: SIGSEGV (segmentation fault)"
    assert failed.loc[102, "error"] == "worker died: SIGABRT (abort)"
    done = df[df["status"] == "done"]
    assert len(done) == 40 and done[METRIC_COLS].notna().all().all()
    assert (done["overhead_s"] > 0).all()
    for a in done["artifacts"]:
        assert (db.parent / a / "metrics.json").is_file() and (db.parent / a / "trajectories.csv").is_file()
    assert (db.parent / "ledger.csv").is_file()

    r = _cli("batch", bf)  # a third time: nothing left to do
    assert "42 of 42 runs already recorded" in r.stdout and ledger.row_hashes(db) == after


def test_dask_cluster_gives_the_same_metrics_as_the_local_pool(tmp_path):
    from dask.distributed import LocalCluster

    specs = batch.expand([OVERTAKING], [1, 2], SHORT, ["apf_sa", "apf"])
    local = batch.BatchConfig(tuple(specs), tmp_path / "local" / "ledger.sqlite", workers=2)
    assert batch.run_batch(local, progress=False)["done"] == 4
    with LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None,
                      processes=True) as cluster:
        rc = main(["batch", str(OVERTAKING), "--seeds", "1-2", "--controller", "apf_sa", "--controller", "apf",
                   *sum((["--set", s] for s in SHORT), []), "--scheduler", cluster.scheduler_address,
                   "--ledger", str(tmp_path / "dask" / "ledger.sqlite"), "--quiet"])
    assert rc == 0
    a = ledger.read(local.ledger).set_index("key")
    b = ledger.read(tmp_path / "dask" / "ledger.sqlite").set_index("key")
    assert sorted(a.index) == sorted(b.index) == sorted(s.key for s in specs)
    cols = METRIC_COLS + ["sa_escapes", "time_to_goal_s"]
    assert a[cols].sort_index().equals(b[cols].sort_index())


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


def test_bad_input_is_one_line_and_writes_nothing(tmp_path):
    db = tmp_path / "l.sqlite"
    for args, words in [(["--seeds", "5-1"], "--seeds"), (["--set", "sim.duration_s=-1"], "sim.duration_s"),
                        (["--workers", "0"], "--workers"), (["--controller", "nope"], "ego.controller")]:
        r = _cli("batch", OVERTAKING, "--ledger", db, *args)
        assert r.returncode == 2, r.stderr
        assert r.stderr.count("\n") == 1 and words in r.stderr and r.stderr.startswith("sumo-avoid: error:")
    bad = tmp_path / "b.toml"
    bad.write_text(f'[[runs]]\nscenario = "{OVERTAKING}"\nseeds = "1-2"\ninject_crash = "meteor"\n')
    r = _cli("batch", bad, "--ledger", db)
    assert r.returncode == 2 and "inject_crash" in r.stderr and r.stderr.count("\n") == 1
    assert not db.exists()


def test_sumo_error_and_timeout_are_recorded_as_failed(tmp_path):
    scn = tmp_path / "s.toml"
    scn.write_text(OVERTAKING.read_text().replace("../nets/", f"{ROOT}/nets/")
                   .replace('"overtaking.rou.xml"', '"bad.rou.xml"'))
    (tmp_path / "bad.rou.xml").write_text((ROOT / "scenarios" / "overtaking.rou.xml").read_text()
                                          .replace('edges="road"', 'edges="no_such_edge"'))
    spec = batch.plan(scn, 1, SHORT)
    res = run_one(spec.to_json(), str(tmp_path / "runs"), 120)
    assert res["status"] == "failed" and "no_such_edge" in res["error"]  # SUMO's own message
    res = run_one(batch.plan(OVERTAKING, 1, SHORT).to_json(), str(tmp_path / "runs"), 0.3)
    assert res == {**res, "status": "failed", "error": "timeout: run exceeded 0.3 s and was killed"}
    assert not any((tmp_path / "runs" / ".tmp").iterdir())  # temporary folders were moved into place


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
