"""One run in a fresh subprocess: ``run_one`` (parent side) and ``python -m sumo_avoid.worker`` (child).

The child loads the scenario, runs it, writes its artifacts (metrics.json, trajectories.csv,
plots, sumo.log) into a private temporary folder and, last, ``result.json`` (atomically). The
parent waits (with a timeout), reads ``result.json`` or, if the child died without one, builds
the failure from its exit status, and moves the folder to ``<root>/<key[:16]>``. ``run_one``
never raises for a failing run, so it works unchanged as a Dask task.

Test-only fault injection: ``inject_crash = "segfault"`` makes the child dereference a NULL
pointer (a real SIGSEGV in native code), ``"abort"`` makes it call ``os.abort()``; both happen
after the scenario is loaded, before SUMO starts. They exist to test crash isolation.
"""
from __future__ import annotations

import datetime
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading
import time
import uuid

CRASHES = ("segfault", "abort")
_LIVE: set = set()  # running worker processes of this (parent) process, for kill_all()
_LIVE_LOCK = threading.Lock()


def kill_all() -> None:
    """Kill every running worker of this process (the batch is being interrupted)."""
    with _LIVE_LOCK:
        for proc in list(_LIVE):
            proc.kill()


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds")


def _signal_name(n: int) -> str:
    try:
        name = signal.Signals(n).name
    except ValueError:
        return f"signal {n}"
    return {"SIGSEGV": "SIGSEGV (segmentation fault)", "SIGABRT": "SIGABRT (abort)",
            "SIGKILL": "SIGKILL (killed)"}.get(name, name)


def _last_line(path: pathlib.Path) -> str:
    try:
        lines = [ln.strip() for ln in path.read_text(errors="replace").splitlines() if ln.strip()]
    except OSError:
        return ""
    return lines[-1][:300] if lines else ""


def run_one(spec: dict, root: str, timeout_s: float) -> dict:
    """Run one spec (RunSpec.to_json()) in a subprocess; return its result dict (never raises)."""
    root_p = pathlib.Path(root)
    tmp = root_p / ".tmp" / f"{spec['key'][:16]}-{uuid.uuid4().hex[:8]}"
    tmp.mkdir(parents=True, exist_ok=True)
    started, t0, spawn_wall = _now(), time.perf_counter(), time.time()
    job = dict(spec, out=str(tmp), spawn_wall=spawn_wall, parent=os.getpid())
    with open(tmp / "stdout.txt", "wb") as out, open(tmp / "stderr.txt", "wb") as err:
        proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.worker", json.dumps(job)],
                                stdout=out, stderr=err, stdin=subprocess.DEVNULL)
        with _LIVE_LOCK:
            _LIVE.add(proc)
        try:
            rc = proc.wait(timeout=timeout_s)
            timed_out = False
        except subprocess.TimeoutExpired:
            proc.kill()
            rc = proc.wait()
            timed_out = True
        except BaseException:  # interrupted parent: take the child down with us
            proc.kill()
            proc.wait()
            raise
        finally:
            with _LIVE_LOCK:
                _LIVE.discard(proc)
    res_file = tmp / "result.json"
    if res_file.is_file() and not timed_out:
        res = json.loads(res_file.read_text())
    elif timed_out:
        res = {"status": "failed", "error": f"timeout: run exceeded {timeout_s:g} s and was killed"}
    elif rc < 0:
        res = {"status": "failed", "error": f"worker died: {_signal_name(-rc)}"}
    else:
        tail = _last_line(tmp / "stderr.txt")
        res = {"status": "failed", "error": f"worker exited with code {rc} and no result" + (f": {tail}" if tail else "")}
    res.update(started_at=started, ended_at=_now(), wall_s=time.perf_counter() - t0)
    final = root_p / spec["key"][:16]
    if final.exists():  # left over from an unfinished earlier attempt (done runs are never re-run)
        shutil.rmtree(final)
    os.replace(tmp, final)
    res["artifacts"] = str(final)
    return res


def _die_with_parent() -> None:
    """Linux: get SIGKILL when the parent dies, so a killed batch leaves no orphan runs."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        pass


def _crash(kind: str) -> None:
    if kind == "segfault":
        import ctypes

        ctypes.string_at(0)  # NULL dereference: SIGSEGV
    elif kind == "abort":
        os.abort()


def child(job: dict) -> int:
    _die_with_parent()
    if os.getppid() != job["parent"]:  # the parent died before prctl took effect
        return 3
    out = pathlib.Path(job["out"])

    def finish(res: dict) -> None:
        part = out / "result.json.part"
        part.write_text(json.dumps(res, sort_keys=True))
        os.replace(part, out / "result.json")

    try:
        from . import evaluate, runner, scenario

        scn = scenario.load(job["scenario"], job["overrides"], controller=job["controller"], seed=job["seed"])
        if job.get("inject_crash"):
            _crash(job["inject_crash"])
        t_run = time.time()
        res = runner.run(scn, log_file=out / "sumo.log", progress=False)
        m = evaluate.write_outputs(res, out, plots=scn.spec.output.plots)
        overhead = t_run + res.timings.get("setup_s", 0.0) - job["spawn_wall"]
        finish({"status": "done", "metrics": m, "overhead_s": overhead, "timings": res.timings})
        return 0
    except Exception as e:  # recorded as the run's failure, one line
        msg = str(e).strip().splitlines()[0] if str(e).strip() else ""
        finish({"status": "failed", "error": f"{type(e).__name__}: {msg}"[:500]})
        return 1


if __name__ == "__main__":
    sys.exit(child(json.loads(sys.argv[1])))
