"""One run in its own process: ``run_one`` (parent side), the fork server and the run itself.

Every run is its own process, so a run that segfaults, aborts or hangs costs only itself. Two
ways to start that process (``start``):

* ``"fork"`` (default on Linux): one warm **fork server** per parent process
  (``python -m sumo_avoid.runs.forkserver PARENT_PID``) imports numpy, pandas, shapely, libsumo and the
  plug-in once, then forks a fresh child per run. The server never runs a simulation itself, so
  every child starts from the same clean, freshly imported state; a child that crashes takes
  nothing with it. The server enforces the run's timeout (``pidfd``, race-free kill) and reports
  the child's exit status. This removes the ~0.6 s of interpreter start and imports from every
  run (measured: ``benchmarks/batch.py``).
* ``"spawn"``: a fresh ``python -m sumo_avoid.runs.worker JOB`` interpreter per run (the only way on
  systems without ``fork``/``pidfd``).

Either way the child loads the scenario, runs it, writes its artifacts (metrics.json,
trajectories.csv, plots, sumo.log) into a private temporary folder and, last, ``result.json``
(atomically). The parent reads ``result.json`` or, if the child died without one, builds the
failure from its exit status, and moves the folder to ``<root>/<key[:16]>``. ``run_one`` never
raises for a failing run, so it works unchanged as a Dask task (each Dask worker process gets its
own fork server).

Test-only fault injection: ``inject_crash = "segfault"`` makes the child dereference a NULL
pointer (a real SIGSEGV in native code), ``"abort"`` makes it call ``os.abort()``; both happen
after the scenario is loaded, before SUMO starts; ``"segfault_mid_run"`` segfaults once the simulation has run
``CRASH_AT_S`` (SUMO running). (A real input that segfaults SUMO 1.28:
``tests/data/segfault_net.toml``, see docs/batch.md.)
"""
from __future__ import annotations

import atexit
import datetime
import faulthandler
import functools
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

_IMPORT_START = (os.getpid(), time.time())  # a spawned run's interpreter imports what follows itself

from sumo_avoid.runs import outputs as evaluate  # noqa: E402
from sumo_avoid.core.config import ScenarioError  # noqa: E402
from sumo_avoid.runs import runner  # noqa: E402
from sumo_avoid.scenario import spec as scenario  # noqa: E402
from sumo_avoid.runs.watch import (  # noqa: E402
    CRASH_AT_S,
    CrashAt,
    ProgressFile,
    cpu_s,
    crash,
    crash_site,
    die_with_parent,
)

_IMPORTED = time.time()

CRASHES = ("segfault", "abort", "segfault_mid_run")
STARTS = ("fork", "spawn")
# One run per core: BLAS thread pools would only oversubscribe the cores, and the fork server
# must stay single-threaded to fork safely.
CHILD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
SERVER_GRACE_S = 120.0  # the server enforces the timeout; the parent gives up on it only this much later
_LIVE: set = set()  # spawn mode: running worker processes of this (parent) process, for kill_all()
_LIVE_LOCK = threading.Lock()


@functools.lru_cache(maxsize=None)
def default_start() -> str:
    """``"fork"`` where the fork server works (Linux with pidfd), else ``"spawn"``."""
    if sys.platform != "linux" or not hasattr(os, "pidfd_open") or not hasattr(signal, "pidfd_send_signal"):
        return "spawn"
    try:
        os.close(os.pidfd_open(os.getpid()))
    except OSError:  # kernel < 5.3 or a sandbox without the syscall
        return "spawn"
    return "fork"


def kill_all() -> None:
    """Kill every running worker of this process (the batch is being interrupted)."""
    with _LIVE_LOCK:
        for proc in list(_LIVE):
            proc.kill()
    with _SERVER_LOCK:
        if _SERVER is not None:
            _SERVER.kill()  # its children get SIGKILL too (PR_SET_PDEATHSIG)


def now() -> str:
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


def _child_env() -> dict:
    return {**os.environ, **CHILD_ENV}


# --- parent side ------------------------------------------------------------------------------
def run_one(spec: dict, root: str, timeout_s: float, start: str | None = None) -> dict:
    """Run one spec (RunSpec.to_json()) in its own process; return its result dict (never raises).

    ``start``: ``"fork"`` (from the warm fork server) or ``"spawn"`` (fresh interpreter);
    default :func:`default_start`.
    """
    root_p = pathlib.Path(root).absolute()  # the fork server's working directory may not be ours
    tmp = root_p / ".tmp" / f"{spec['key'][:16]}-{uuid.uuid4().hex[:8]}"
    tmp.mkdir(parents=True, exist_ok=True)
    res = run_in(tmp, spec, timeout_s, start)
    (tmp / "result.json").write_text(json.dumps(res, sort_keys=True))  # now with the parent's side and timings
    final = root_p / spec["key"][:16]
    if final.exists():  # left over from an unfinished earlier attempt (done runs are never re-run)
        shutil.rmtree(final)
    os.replace(tmp, final)
    res["artifacts"] = str(final)
    return res


def run_in(tmp: pathlib.Path, spec: dict, timeout_s: float, start: str | None = None) -> dict:
    """Run one spec in its own process with ``tmp`` (an existing folder) as its output folder;
    return its result dict (never raises for a failing run). (``sumo-avoid run`` forks its one run
    from its own process instead: :mod:`sumo_avoid.runs.isolate`.)"""
    start = start or default_start()
    if start not in STARTS:
        raise ValueError(f"start must be one of {STARTS}, not {start!r}")
    started, t0 = now(), time.perf_counter()
    job = dict(spec, out=str(pathlib.Path(tmp).absolute()), timeout_s=timeout_s, id=pathlib.Path(tmp).name)
    if start == "fork":
        status = _run_forked(job, timeout_s)
    else:
        status = _run_spawned(job, pathlib.Path(tmp), timeout_s)
    res = result_of(pathlib.Path(tmp), status, timeout_s)
    res.update(started_at=started, ended_at=now(), wall_s=time.perf_counter() - t0, start=start)
    res["marks"]["ended_wall"] = time.time()
    return res


def result_of(tmp: pathlib.Path, status: dict, timeout_s: float) -> dict:
    """The run's result: its result.json, or the failure its exit status tells."""
    res_file = tmp / "result.json"
    rc, timed_out = status.get("rc"), status.get("timed_out", False)
    if res_file.is_file() and not timed_out:
        res = json.loads(res_file.read_text())
    elif timed_out:
        res = {"status": "failed", "error": f"timeout: run exceeded {timeout_s:g} s and was killed"}
    elif status.get("error"):
        res = {"status": "failed", "error": status["error"]}
    elif rc < 0:
        res = {"status": "failed", "error": f"worker died: {_signal_name(-rc)}"}
        where = crash_site(tmp / "stderr.txt")
        if where:
            res["where"] = where
    else:
        tail = _last_line(tmp / "stderr.txt")
        res = {"status": "failed", "error": f"worker exited with code {rc} and no result" + (f": {tail}" if tail else "")}
    marks = dict(res.get("marks", {}), **{k: v for k, v in status.items() if k.endswith("_wall")})
    if "sumo_start_wall" in marks:
        res["overhead_s"] = marks["sumo_start_wall"] - marks["dispatch_wall"]
    res["marks"] = marks
    return res


def _run_spawned(job: dict, tmp: pathlib.Path, timeout_s: float) -> dict:
    job.update(dispatch_wall=time.time(), parent=os.getpid())
    with open(tmp / "stdout.txt", "wb") as out, open(tmp / "stderr.txt", "wb") as err:
        proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.runs.worker", json.dumps(job)],
                                stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=_child_env())
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
    return {"rc": rc, "timed_out": timed_out, "dispatch_wall": job["dispatch_wall"], "reaped_wall": time.time()}


class _Server:
    """Parent side of one fork server: writes jobs to its stdin, a reader thread hands the replies
    (one JSON line per finished run, matched by job id) to the waiting ``run_one`` calls."""

    def __init__(self):
        self.proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.runs.forkserver", str(os.getpid())],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=_child_env())
        self.lock = threading.Lock()
        self.waiting: dict[str, list] = {}  # job id -> [Event, reply or None]
        self.ready: dict = {}  # the server's first line: pid, import_s
        self.dead: str | None = None
        threading.Thread(target=self._read, name="sumo-avoid-fork-server", daemon=True).start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            msg = json.loads(line)
            if "id" not in msg:
                self.ready = msg
                continue
            with self.lock:
                waiter = self.waiting.pop(msg["id"], None)
            if waiter is not None:
                waiter[1] = msg
                waiter[0].set()
        rc = self.proc.wait()
        with self.lock:
            self.dead = f"exited with code {rc}" if rc >= 0 else f"died: {_signal_name(-rc)}"
            waiters, self.waiting = list(self.waiting.values()), {}
        for w in waiters:
            w[0].set()

    def submit(self, job: dict) -> list | None:
        """Hand a job over; None if the server is gone."""
        waiter = [threading.Event(), None]
        with self.lock:
            if self.dead is not None:
                return None
            self.waiting[job["id"]] = waiter
            try:
                self.proc.stdin.write(json.dumps(job).encode() + b"\n")
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError):  # died (or was closed) since: the reader will notice
                self.waiting.pop(job["id"], None)
                return None
        return waiter

    def kill(self) -> None:
        self.proc.kill()

    def close(self, wait_s: float = 2.0) -> None:
        """EOF on its stdin: the server exits (killing any child still running); SIGKILL after ``wait_s``,
        or at once if it is still importing (it never ran anything)."""
        if not self.ready:
            self.kill()
        try:
            self.proc.stdin.close()
            self.proc.wait(wait_s)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
            self.proc.wait()


_SERVER: _Server | None = None
_SERVER_LOCK = threading.Lock()


def _server() -> _Server:
    global _SERVER
    with _SERVER_LOCK:
        if _SERVER is None or _SERVER.dead is not None or _SERVER.proc.poll() is not None:
            _SERVER = _Server()
        return _SERVER


def prestart(wait: bool = False) -> dict:
    """Start this process's fork server now, so its imports overlap with other work; with ``wait``,
    also wait until its imports are done. Returns :func:`server_info`."""
    if default_start() == "fork":
        server = _server()
        while wait and not server.ready and server.dead is None:
            time.sleep(0.01)
    return server_info()


def server_info() -> dict:
    """The running fork server's ``pid``, ``import_s`` (its start-up imports) and ``threads``;
    {} if there is none or it is still importing."""
    server = _SERVER
    return dict(server.ready) if server is not None and server.dead is None else {}


def shutdown() -> None:
    """Stop this process's fork server (the next fork-mode run starts a new one)."""
    global _SERVER
    with _SERVER_LOCK:
        server, _SERVER = _SERVER, None
    if server is not None:
        server.close()


atexit.register(shutdown)


def _run_forked(job: dict, timeout_s: float) -> dict:
    job["dispatch_wall"] = time.time()
    server = _server()
    waiter = server.submit(job)
    if waiter is None:  # it died between runs (e.g. killed by hand): one fresh start, then give up
        server = _server()
        waiter = server.submit(job)
    if waiter is None:
        return {"error": f"worker died: the fork server {server.dead}", "dispatch_wall": job["dispatch_wall"]}
    if not waiter[0].wait(timeout_s + SERVER_GRACE_S):  # the server itself hangs: nothing else can stop the run
        server.kill()
        return {"timed_out": True, "dispatch_wall": job["dispatch_wall"]}
    reply = waiter[1]
    if reply is None:
        return {"error": f"worker died: the fork server {server.dead}", "dispatch_wall": job["dispatch_wall"]}
    reply["notified_wall"] = time.time()
    reply["dispatch_wall"] = job["dispatch_wall"]
    return reply


def exit_now(rc: int) -> None:
    """Flush stdio and exit without the interpreter's teardown: nothing in it is needed once
    result.json is written, and in a spawned worker it took 0.40 s (median, benchmarks/batch.py on
    a loaded 2-core machine) of freeing pandas, numpy, libsumo...; 0.05 s from result to reaped
    with this."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:
            pass
    os._exit(rc)


# --- the run (in the child) ---------------------------------------------------------------------
def child(job: dict) -> int:
    own_imports = _IMPORT_START[0] == os.getpid()  # spawned: this process imported the run's modules
    marks = {"entry_wall": _IMPORT_START[1] if own_imports else time.time()}
    faulthandler.enable(file=2)  # a fatal signal writes the Python stack to stderr.txt: where the run died
    die_with_parent()
    if os.getppid() != job["parent"]:  # the parent died before prctl took effect
        return 3
    out = pathlib.Path(job["out"])

    def finish(res: dict) -> None:
        res["marks"] = marks
        part = out / "result.json.part"
        part.write_text(json.dumps(res, sort_keys=True))
        os.replace(part, out / "result.json")

    try:
        marks["imported_wall"] = _IMPORTED if own_imports else time.time()
        scn = scenario.load(job["scenario"], job["overrides"], controller=job["controller"], seed=job["seed"])
        marks["loaded_wall"] = time.time()
        kind = job.get("inject_crash")
        if kind in ("segfault", "abort"):
            crash(kind)
        t_run = time.time()
        watch = [ProgressFile(job["progress_file"])] if job.get("progress_file") else []
        if kind == "segfault_mid_run":
            watch.append(CrashAt(CRASH_AT_S))
        res = runner.run(scn, log_file=out / "sumo.log", progress=False, callbacks=watch)
        marks["sumo_start_wall"] = t_run + res.timings.get("setup_s", 0.0)  # road and controllers set up
        marks["run_end_wall"] = time.time()
        m = evaluate.write_outputs(res, out, plots=scn.spec.output.plots and job.get("plots", True))
        marks["written_wall"] = time.time()
        finish({"status": "done", "metrics": m, "timings": res.timings, "cpu_s": cpu_s()})
        return 0
    except ScenarioError as e:  # bad input found only once SUMO ran: the caller reports it as such
        finish({"status": "failed", "error": f"ScenarioError: {e}"[:500], "bad_input": str(e)})
        return 1
    except Exception as e:  # recorded as the run's failure, one line
        msg = str(e).strip().splitlines()[0] if str(e).strip() else ""
        finish({"status": "failed", "error": f"{type(e).__name__}: {msg}"[:500]})
        return 1




if __name__ == "__main__":
    exit_now(child(json.loads(sys.argv[1])))
