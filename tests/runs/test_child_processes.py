"""Every run in its own process, on real libsumo: a crash, a timeout or an exception costs only its
run; the fork server (warm imports, one forked process per run) gives what a fresh interpreter gives;
a SIGKILLed batch leaves no process behind and resumes; Ctrl-C kills the running runs.

Runs are short (5 s of simulated time, no plots). Crashes are real: a net that segfaults SUMO, and
test-only injection through the environment (:mod:`sumo_avoid.runs.faults`).
"""
import contextlib
import dataclasses
import json
import os
import pathlib
import signal
import sqlite3
import subprocess
import sys
import threading
import time

import pytest
from conftest import METRIC_COLS, OVERTAKING, SHORT, cli_in_process

from sumo_avoid.runs import faults, worker
from sumo_avoid.runs.worker import run_in, run_one
from sumo_avoid.studies import batch, ledger, table4

pytestmark = pytest.mark.sumo
ROOT = pathlib.Path(__file__).resolve().parents[2]
SEGFAULT_NET = ROOT / "tests" / "data" / "segfault_net.toml"  # a real input that segfaults SUMO 1.28 on load


def _cli(*args, env=None, **kw):
    return subprocess.run([sys.executable, "-m", "sumo_avoid.cli", *map(str, args)], capture_output=True,
                          text=True, cwd=ROOT, env={**os.environ, "CI": "true", **(env or {})}, **kw)


def _batch_file(tmp_path, seeds="1-5") -> pathlib.Path:
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

[[runs]]   # a broken net: SUMO itself segfaults while loading it (no injection)
scenario = "{SEGFAULT_NET}"
seeds = [101]
set = {SHORT!r}

[[runs]]   # made to abort (test-only injection: ABORT_102 in the environment)
scenario = "{OVERTAKING}"
seeds = [102]
set = {SHORT!r}
""".replace("'", '"'))
    return f


ABORT_102 = {faults.ENV: "abort:102"}


def _job_parent(arg: str):
    try:
        return json.loads(arg).get("parent")
    except (ValueError, AttributeError):
        return None


def _alive_workers(batch_pid: int) -> list[int]:
    """Worker processes of the batch process ``batch_pid``: its fork server and the runs forked
    from it (``-m sumo_avoid.runs.forkserver PID``) or spawned runs (``"parent": PID`` in the message)."""
    pids = []
    for p in pathlib.Path("/proc").iterdir():
        try:
            args = (p / "cmdline").read_bytes().decode(errors="replace").split("\0")
        except OSError:
            continue
        if not p.name.isdigit():
            continue
        if ("sumo_avoid.runs.forkserver" in args and args[-2:-1] == [str(batch_pid)]
                or "sumo_avoid.runs.child" in args and _job_parent(args[-2]) == batch_pid):
            pids.append(int(p.name))
    return pids


def _kill_midway(proc, db, at: int) -> dict:
    """SIGKILL the batch once ``at`` runs are recorded; return the row hashes at that moment."""
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
            if n >= at:
                break
    assert proc.poll() is None, "batch finished before it could be killed"
    assert _alive_workers(proc.pid), "no worker processes found: the check below would prove nothing"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    time.sleep(1.0)
    assert _alive_workers(proc.pid) == []  # EOF + PDEATHSIG: no fork server, no orphaned runs
    return ledger.row_hashes(db)


def test_crashes_cost_only_their_run_and_sigkilled_batch_resumes(tmp_path, monkeypatch):
    bf = _batch_file(tmp_path)
    specs, opts = batch.load_batch_file(bf)
    assert len(specs) == 12  # 5 seeds x 2 controllers, and the two crashing runs
    db = opts["ledger"]
    sys_tmp = tmp_path / "sys_tmp"  # the system's temp folder for the killed batch
    sys_tmp.mkdir()
    proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.cli", "batch", str(bf)], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env={**os.environ, "CI": "true", "TMPDIR": str(sys_tmp), **ABORT_102})
    try:
        before = _kill_midway(proc, db, at=4)
    finally:
        proc.kill()
    assert 4 <= len(before) < 12
    # the killed runs' temporary files (SUMO's SSM output, rewritten route files) are in their partial run
    # folders beside the ledger, which the resume removes: none in the system's temp folder (one each, for good)
    assert not list(sys_tmp.glob("sumo-avoid-*")), sorted(p.name for p in sys_tmp.iterdir())

    r = _cli("batch", bf, env=ABORT_102)
    assert r.returncode == 1, r.stderr  # 1: the batch has failed runs
    assert f"{len(before)} of 12 runs already recorded" in r.stdout
    df = ledger.read(db)
    assert sorted(df["key"]) == sorted(s.key for s in specs)  # every run exactly once
    after = ledger.row_hashes(db)
    assert all(after[k] == h for k, h in before.items())  # nothing finished was rewritten
    failed = df[df["status"] == "failed"].set_index("seed")
    assert sorted(failed.index) == [101, 102]
    assert failed.loc[101, "scenario"] == "segfault_net"
    assert failed.loc[101, "error"] == "worker died: SIGSEGV (segmentation fault)"
    assert failed.loc[102, "error"] == "worker died: SIGABRT (abort)"
    done = df[df["status"] == "done"]
    assert len(done) == 10 and done[METRIC_COLS].notna().all().all()
    assert (done["overhead_s"] > 0).all()
    for a in done["artifacts"]:
        assert (db.parent / a / "metrics.json").is_file() and (db.parent / a / "trajectories.csv").is_file()
    assert (db.parent / "ledger.csv").is_file()
    assert not list((db.parent / ".tmp").glob("*"))  # the killed runs' partial folders went with the resume

    r = cli_in_process("batch", bf, cwd=ROOT)  # a third time: nothing left to do (nothing starts SUMO: in process)
    assert "12 of 12 runs already recorded" in r.stdout and ledger.row_hashes(db) == after
    assert (done["code"] == ledger.code_version()).all() and "other plug-in code" not in r.stdout

    with sqlite3.connect(db) as con:  # as if two runs had been made by an earlier version of the code
        con.execute("UPDATE runs SET code = 'earlier' WHERE key IN (SELECT key FROM runs WHERE status = 'done' LIMIT 2)")
    before = ledger.row_hashes(db)
    r = cli_in_process("batch", bf, cwd=ROOT)
    assert "warning: 2 of them were made by other plug-in code" in r.stdout
    assert ledger.row_hashes(db) == before  # told, not re-run or rewritten


def test_ctrl_c_kills_the_running_runs_and_records_none_of_them(tmp_path):
    db = tmp_path / "ledger.sqlite"
    proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.cli", "batch", str(OVERTAKING), "--seeds", "1-20",
                             "--set", "output.plots=false", "--workers", "2", "--ledger", str(db)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env={**os.environ, "CI": "true"},
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # as in a terminal
    try:
        deadline = time.time() + 60
        while len(_alive_workers(proc.pid)) < 3 and time.time() < deadline:  # the server and two runs
            time.sleep(0.05)
        assert len(_alive_workers(proc.pid)) >= 3
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 130 and "interrupted" in err
    time.sleep(0.5)
    assert _alive_workers(proc.pid) == []
    with contextlib.closing(sqlite3.connect(db)) as con:
        assert con.execute("SELECT count(*) FROM runs WHERE status = 'failed'").fetchone()[0] == 0


@pytest.mark.parametrize("start", [*worker.STARTS, "here"])
def test_sumo_error_and_timeout_are_recorded_as_failed(tmp_path, start):
    scn = tmp_path / "s.toml"
    scn.write_text(OVERTAKING.read_text().replace("../nets/", f"{ROOT}/nets/")
                   .replace('"overtaking.rou.xml"', '"bad.rou.xml"'))
    # a vType SUMO refuses when it loads it (an unknown edge is now found before the run: sumo/inputs.py)
    (tmp_path / "bad.rou.xml").write_text((ROOT / "scenarios" / "overtaking.rou.xml").read_text()
                                          .replace('accel="2.6"', 'accel="-3"'))
    (tmp_path / "a").mkdir()
    res = run_in(tmp_path / "a", batch.plan(scn, 1, SHORT).job(), 120, start)
    assert res.status == "failed" and "Invalid parsing embedded VType" in res.error  # SUMO's own message
    # the whole 90 s scenario: well over 0.3 s of wall time even without interpreter start
    (tmp_path / "b").mkdir()
    res = run_in(tmp_path / "b", batch.plan(OVERTAKING, 1, ["output.plots=false"]).job(), 0.3, start)
    assert (res.status, res.error, res.start) == ("timeout", "timeout: run exceeded 0.3 s and was killed", start)
    assert res.ledger_status == "failed" and res.metrics is None


def test_run_one_moves_the_run_into_place(tmp_path):
    spec = batch.plan(OVERTAKING, 1, SHORT)
    res = run_one(spec.job(), str(tmp_path / "runs"), 120)
    assert res.ok and res.artifacts == str(tmp_path / "runs" / spec.key[:16])
    assert not any((tmp_path / "runs" / ".tmp").iterdir())  # the temporary folder was moved into place
    assert json.loads((pathlib.Path(res.artifacts) / "metrics.json").read_text()) == res.metrics
    assert json.loads((pathlib.Path(res.artifacts) / "result.json").read_text())["artifacts"] is None  # as run_in gave it


def test_a_job_kind_runs_its_function_in_the_child_and_a_missing_one_fails_before_sumo(tmp_path):
    job = table4.table4_job(4, 1, agents=3, duration=1.0)
    (tmp_path / "ok").mkdir()
    res = run_in(tmp_path / "ok", job, 120)
    assert res.ok and (res.metrics["v"], res.metrics["seed"]) == (4, 1) and 0 <= res.metrics["mu"] <= 1
    (tmp_path / "bad").mkdir()
    res = run_in(tmp_path / "bad", dataclasses.replace(job, kind="sumo_avoid.studies.table4:nope"), 120)
    assert (res.status, res.error) == ("failed", "AttributeError: module 'sumo_avoid.studies.table4' has no "
                                                 "attribute 'nope'")
    assert "sumo_start_wall" not in res.clock_s  # found out before SUMO started


def _same_files(a, b, names=("metrics.json", "trajectories.csv")) -> bool:
    return all((pathlib.Path(a) / n).read_bytes() == (pathlib.Path(b) / n).read_bytes() for n in names)


def test_forked_run_equals_fresh_interpreter_run_and_skips_the_imports(tmp_path):
    job = batch.plan(OVERTAKING, 3, SHORT).job()
    worker.prestart()
    runs = {start: run_one(job, str(tmp_path / start), 120, start) for start in ("fork", "spawn")}
    fork, spawn = runs["fork"], runs["spawn"]
    assert fork.status == spawn.status == "done"
    assert _same_files(fork.artifacts, spawn.artifacts)  # byte-identical results
    # the forked child finds everything imported; the fresh interpreter imports numpy, pandas, libsumo...
    assert fork.clock_s["imported_wall"] - fork.clock_s["entry_wall"] < 0.1
    assert spawn.clock_s["imported_wall"] - spawn.clock_s["entry_wall"] > 0.2
    for res in runs.values():
        clock = res.clock_s
        assert clock["dispatch_wall"] <= clock["entry_wall"] <= clock["sumo_start_wall"] <= clock["reaped_wall"]
        assert res.overhead_s == pytest.approx(clock["sumo_start_wall"] - clock["dispatch_wall"])
    assert fork.clock_s["dispatch_wall"] <= fork.clock_s["fork_wall"] <= fork.clock_s["entry_wall"]


def test_forked_run_writes_plots(tmp_path):
    spec = batch.plan(OVERTAKING, 1, ["sim.duration_s=5"])
    assert spec.plots  # the fork server imports matplotlib before forking this run
    res = run_one(spec.job(), str(tmp_path), 120, "fork")
    assert res.status == "done"
    assert all((pathlib.Path(res.artifacts) / f).stat().st_size > 0 for f in ("trajectory.png", "timeseries.png"))


@pytest.mark.parametrize("start", worker.STARTS)
def test_a_crashing_run_costs_only_itself(tmp_path, start, monkeypatch):
    job = batch.plan(OVERTAKING, 1, SHORT).job()
    runs = {"segfault_net": (batch.plan(SEGFAULT_NET, 1, SHORT).job(), ""),  # SUMO's own SIGSEGV
            "segfault": (job, "segfault:*"),  # NULL dereference
            "abort": (job, f"abort:{job.key[:12]}")}
    if start == "fork":
        worker.prestart()
        server = worker._server().proc.pid
    outcomes = {}
    for name, (j, inject) in runs.items():
        monkeypatch.setenv(faults.ENV, inject)  # read at dispatch: the running fork server needs no restart
        outcomes[name] = run_one(j, str(tmp_path), 120, start)
    assert {name: (o.status, o.error) for name, o in outcomes.items()} == {
        "segfault_net": ("crashed", "worker died: SIGSEGV (segmentation fault)"),
        "segfault": ("crashed", "worker died: SIGSEGV (segmentation fault)"),
        "abort": ("crashed", "worker died: SIGABRT (abort)")}
    assert outcomes["segfault"].where.endswith("(string_at)")  # faulthandler's frame: the injected NULL read
    monkeypatch.delenv(faults.ENV)
    assert run_one(job, str(tmp_path), 120, start).status == "done"  # the same job, no injection
    if start == "fork":
        assert worker._server().proc.pid == server  # the server outlived its crashing children


def test_a_dead_fork_server_fails_its_runs_and_is_replaced(tmp_path):
    worker.prestart()
    server = worker._server()
    out = {}
    job = batch.plan(OVERTAKING, 1, ["output.plots=false"]).job()  # the whole scenario: seconds
    t = threading.Thread(target=lambda: out.update(res=run_one(job, str(tmp_path), 120, "fork")))
    t.start()
    deadline = time.time() + 30
    while not server.waiting and time.time() < deadline:
        time.sleep(0.01)
    time.sleep(0.3)  # the run is forked and going
    server.kill()
    t.join(30)
    assert (out["res"].status, out["res"].error) == ("crashed", "worker died: the fork server died: SIGKILL (killed)")
    time.sleep(0.5)
    assert _alive_workers(os.getpid()) == []  # its child went with it (PR_SET_PDEATHSIG)
    res = run_one(batch.plan(OVERTAKING, 2, SHORT).job(), str(tmp_path), 120, "fork")
    assert res.status == "done" and worker._server() is not server
