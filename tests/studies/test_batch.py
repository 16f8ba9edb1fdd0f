"""Batches on real libsumo: crash isolation, SIGKILL + resume, bad input (Dask: test_dask.py),
the fork server (warm imports, one forked process per run) against fresh interpreters.

Runs are short (5 s of simulated time, no plots) to keep the whole file around a minute.
"""
import contextlib
import json
import os
import pathlib
import shutil
import signal
import sqlite3
import subprocess
import sys
import time

import pytest
from conftest import METRIC_COLS, OVERTAKING, SHORT, cli_in_process

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs import worker
from sumo_avoid.studies import batch, ledger
from sumo_avoid.runs.worker import run_one

ROOT = pathlib.Path(__file__).resolve().parents[2]
SEGFAULT_NET = ROOT / "tests" / "data" / "segfault_net.toml"  # a real input that segfaults SUMO 1.28 on load


def _cli(*args, **kw):
    return subprocess.run([sys.executable, "-m", "sumo_avoid.cli", *map(str, args)], capture_output=True,
                          text=True, cwd=ROOT, env={**os.environ, "CI": "true"}, **kw)


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

[[runs]]   # test-only fault injection: os.abort() in the worker
scenario = "{OVERTAKING}"
seeds = [102]
set = {SHORT!r}
inject_crash = "abort"
""".replace("'", '"'))
    return f


def _job_parent(arg: str):
    try:
        return json.loads(arg).get("parent")
    except (ValueError, AttributeError):
        return None


def _alive_workers(batch_pid: int) -> list[int]:
    """Worker processes of the batch process ``batch_pid``: its fork server and the runs forked
    from it (``-m sumo_avoid.runs.forkserver PID``) or spawned runs (``"parent": PID`` in the job)."""
    pids = []
    for p in pathlib.Path("/proc").iterdir():
        try:
            args = (p / "cmdline").read_bytes().decode(errors="replace").split("\0")
        except OSError:
            continue
        if not p.name.isdigit():
            continue
        if ("sumo_avoid.runs.forkserver" in args and args[-2:-1] == [str(batch_pid)]
                or "sumo_avoid.runs.worker" in args and _job_parent(args[-2]) == batch_pid):
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
    before = ledger.row_hashes(db)
    return before


def test_crashes_cost_only_their_run_and_sigkilled_batch_resumes(tmp_path):
    bf = _batch_file(tmp_path)
    specs, opts = batch.load_batch_file(bf)
    assert len(specs) == 12  # 5 seeds x 2 controllers, and the two crashing runs
    db = opts["ledger"]
    proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.cli", "batch", str(bf)], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env={**os.environ, "CI": "true"})
    try:
        before = _kill_midway(proc, db, at=4)
    finally:
        proc.kill()
    assert 4 <= len(before) < 12

    r = _cli("batch", bf)
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
                        (["--workers", "0"], "--workers"), (["--controller", "nope"], "ego.controller"),
                        (["--start", "vfork"], "--start")]:
        r = cli_in_process("batch", OVERTAKING, "--ledger", db, *args, cwd=ROOT)
        assert r.returncode == 2, r.stderr
        assert r.stderr.count("\n") == 1 and words in r.stderr and r.stderr.startswith("sumo-avoid: error:")
    bad = tmp_path / "b.toml"
    bad.write_text(f'[[runs]]\nscenario = "{OVERTAKING}"\nseeds = "1-2"\ninject_crash = "meteor"\n')
    r = _cli("batch", bad, "--ledger", db)
    assert r.returncode == 2 and "inject_crash" in r.stderr and r.stderr.count("\n") == 1
    assert not db.exists()


@pytest.mark.parametrize("start", worker.STARTS)
def test_sumo_error_and_timeout_are_recorded_as_failed(tmp_path, start):
    scn = tmp_path / "s.toml"
    scn.write_text(OVERTAKING.read_text().replace("../nets/", f"{ROOT}/nets/")
                   .replace('"overtaking.rou.xml"', '"bad.rou.xml"'))
    # a vType SUMO refuses when it loads it (an unknown edge is now found before the run: sumo/inputs.py)
    (tmp_path / "bad.rou.xml").write_text((ROOT / "scenarios" / "overtaking.rou.xml").read_text()
                                          .replace('accel="2.6"', 'accel="-3"'))
    spec = batch.plan(scn, 1, SHORT)
    res = run_one(spec.to_json(), str(tmp_path / "runs"), 120, start)
    assert res["status"] == "failed" and "Invalid parsing embedded VType" in res["error"]  # SUMO's own message
    # the whole 90 s scenario: well over 0.3 s of wall time even without interpreter start
    res = run_one(batch.plan(OVERTAKING, 1, ["output.plots=false"]).to_json(), str(tmp_path / "runs"), 0.3, start)
    assert res == {**res, "status": "failed", "error": "timeout: run exceeded 0.3 s and was killed", "start": start}
    assert not any((tmp_path / "runs" / ".tmp").iterdir())  # temporary folders were moved into place


def _same_files(a, b, names=("metrics.json", "trajectories.csv")) -> bool:
    return all((pathlib.Path(a) / n).read_bytes() == (pathlib.Path(b) / n).read_bytes() for n in names)


def test_forked_run_equals_fresh_interpreter_run_and_skips_the_imports(tmp_path):
    spec = batch.plan(OVERTAKING, 3, SHORT).to_json()
    worker.prestart()
    runs = {start: run_one(spec, str(tmp_path / start), 120, start) for start in ("fork", "spawn")}
    fork, spawn = runs["fork"], runs["spawn"]
    assert fork["status"] == spawn["status"] == "done"
    assert _same_files(fork["artifacts"], spawn["artifacts"])  # byte-identical results
    # the forked child finds everything imported; the fresh interpreter imports numpy, pandas, libsumo...
    assert fork["marks"]["imported_wall"] - fork["marks"]["entry_wall"] < 0.1
    assert spawn["marks"]["imported_wall"] - spawn["marks"]["entry_wall"] > 0.2
    for res in runs.values():
        marks = res["marks"]
        assert marks["dispatch_wall"] <= marks["entry_wall"] <= marks["sumo_start_wall"] <= marks["reaped_wall"]
        assert res["overhead_s"] == pytest.approx(marks["sumo_start_wall"] - marks["dispatch_wall"])
    assert fork["marks"]["dispatch_wall"] <= fork["marks"]["fork_wall"] <= fork["marks"]["entry_wall"]


def test_forked_run_writes_plots(tmp_path):
    spec = batch.plan(OVERTAKING, 1, ["sim.duration_s=5"])
    assert spec.plots  # the fork server imports matplotlib before forking this run
    res = run_one(spec.to_json(), str(tmp_path), 120, "fork")
    assert res["status"] == "done"
    assert all((pathlib.Path(res["artifacts"]) / f).stat().st_size > 0 for f in ("trajectory.png", "timeseries.png"))


@pytest.mark.parametrize("start", worker.STARTS)
def test_a_crashing_run_costs_only_itself(tmp_path, start):
    specs = {"segfault_net": batch.plan(SEGFAULT_NET, 1, SHORT),  # SUMO's own SIGSEGV
             "segfault": batch.plan(OVERTAKING, 1, SHORT, inject_crash="segfault"),  # NULL dereference
             "abort": batch.plan(OVERTAKING, 1, SHORT, inject_crash="abort")}
    ok = batch.plan(OVERTAKING, 1, SHORT)
    if start == "fork":
        worker.prestart()
        server = worker._server().proc.pid
    errors = {name: run_one(s.to_json(), str(tmp_path), 120, start)["error"] for name, s in specs.items()}
    assert errors == {"segfault_net": "worker died: SIGSEGV (segmentation fault)",
                      "segfault": "worker died: SIGSEGV (segmentation fault)",
                      "abort": "worker died: SIGABRT (abort)"}
    assert run_one(ok.to_json(), str(tmp_path), 120, start)["status"] == "done"
    if start == "fork":
        assert worker._server().proc.pid == server  # the server outlived its crashing children


def test_a_dead_fork_server_fails_its_runs_and_is_replaced(tmp_path):
    import threading

    worker.prestart()
    server = worker._server()
    out = {}
    spec = batch.plan(OVERTAKING, 1, ["output.plots=false"]).to_json()  # the whole scenario: seconds
    t = threading.Thread(target=lambda: out.update(run_one(spec, str(tmp_path), 120, "fork")))
    t.start()
    deadline = time.time() + 30
    while not server.waiting and time.time() < deadline:
        time.sleep(0.01)
    time.sleep(0.3)  # the run is forked and going
    server.kill()
    t.join(30)
    assert out["status"] == "failed" and out["error"] == "worker died: the fork server died: SIGKILL (killed)"
    time.sleep(0.5)
    assert _alive_workers(os.getpid()) == []  # its child went with it (PR_SET_PDEATHSIG)
    res = run_one(batch.plan(OVERTAKING, 2, SHORT).to_json(), str(tmp_path), 120, "fork")
    assert res["status"] == "done" and worker._server() is not server


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