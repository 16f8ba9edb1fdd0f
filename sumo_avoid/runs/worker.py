"""One run in its own fresh process, parent side: :func:`run_in` / :func:`run_one` take a
:class:`~sumo_avoid.runs.job.RunJob` and return its :class:`~sumo_avoid.runs.job.RunOutcome`.

Every run is its own process (libsumo runs one simulation per process), so a run that segfaults,
aborts or hangs costs only itself. Three ways to start that process (``start``), one child
(:func:`sumo_avoid.runs.child.run`):

* ``"fork"`` (default on Linux): one warm **fork server** per parent process
  (``python -m sumo_avoid.runs.forkserver PARENT_PID``) imports numpy, pandas, shapely, libsumo and the
  plug-in once, then forks a fresh child per run. The server never runs a simulation itself, so
  every child starts from the same clean, freshly imported state; a child that crashes takes
  nothing with it. The server enforces the run's timeout (``pidfd``, race-free kill) and reports
  the child's exit status. This removes the interpreter start and imports from every run
  (``benchmarks/batch.py`` measures it).
* ``"spawn"``: a fresh ``python -m sumo_avoid.runs.child MESSAGE`` interpreter per run (the only way on
  systems without ``fork``/``pidfd``).
* ``"here"``: a child forked from the calling process itself, which must be single-threaded and
  has imported what a run needs (``sumo-avoid run``: a fork server would import everything a second
  time, ~2.5 s); ``poll`` is called while it runs (a progress bar).

The child writes the run's artifacts into a private folder and, last, ``result.json``. The parent
reads it or, if the child died without one, builds the outcome from its exit status; :func:`run_one`
then moves the folder to ``<root>/<key[:16]>``. Neither raises for a failing run, so ``run_one``
works unchanged as a Dask task (each Dask worker process gets its own fork server). Test-only
fault injection (:mod:`sumo_avoid.runs.faults`) is read here, at dispatch, and sent beside the job.
"""
from __future__ import annotations

import atexit
import dataclasses
import datetime
import functools
import json
import math
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading
import time
import uuid

from sumo_avoid.core.output_error import OutputError, from_errno, writing
from sumo_avoid.runs import faults
from sumo_avoid.runs.child import enter
from sumo_avoid.runs.job import UNWRITABLE_RC, RunJob, RunOutcome
from sumo_avoid.runs.watch import crash_site

STARTS = ("fork", "spawn")  # what a batch may choose (``"here"`` is for a single-threaded caller: run_in)
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
def run_one(job: RunJob, root: str, timeout_s: float, start: str | None = None) -> RunOutcome:
    """Run ``job`` in its own process with its artifacts in ``<root>/<key[:16]>``; never raises. A run whose
    files cannot be written (a full disk, a read-only or vanished folder) has ``unwritable`` set and
    leaves no folder.

    ``start``: ``"fork"`` (from the warm fork server) or ``"spawn"`` (fresh interpreter);
    default :func:`default_start`.
    """
    root_p = pathlib.Path(root).absolute()  # the fork server's working directory may not be ours
    tmp = root_p / ".tmp" / f"{job.key[:16]}-{uuid.uuid4().hex[:8]}"
    final = root_p / job.key[:16]
    try:
        with writing(tmp):
            for d in (root_p, tmp.parent, tmp):  # no parents: a folder above ``root`` that vanished is not made again
                d.mkdir(exist_ok=True)
        res = run_in(tmp, job, timeout_s, start)
        if res.unwritable is None:
            with writing(tmp / "result.json"):
                (tmp / "result.json").write_text(json.dumps(res.to_json(), sort_keys=True))  # with the parent's side
            with writing(final):
                if final.exists():  # left over from an unfinished earlier attempt (done runs are never re-run)
                    shutil.rmtree(final)
                os.replace(tmp, final)
            return dataclasses.replace(res, artifacts=str(final))
    except OutputError as e:
        res = RunOutcome("failed", error=str(e), unwritable=[e.path, e.reason])
    shutil.rmtree(tmp, ignore_errors=True)  # nothing half-written: the run's partial folder goes
    return res


def run_in(tmp: pathlib.Path, job: RunJob, timeout_s: float = math.inf, start: str | None = None,
           poll=None, every_s: float = 0.2) -> RunOutcome:
    """Run ``job`` in its own process with ``tmp`` (an existing folder) as its output folder; return
    its outcome (never raises for a failing run; an interrupt kills the child and is raised).
    ``start``: ``"fork"``, ``"spawn"`` or ``"here"`` (module doc); ``poll()``: ``"here"`` only, every ``every_s``."""
    start = start or default_start()
    if start not in (*STARTS, "here"):
        raise ValueError(f"start must be one of {(*STARTS, 'here')}, not {start!r}")
    tmp = pathlib.Path(tmp).absolute()
    job = dataclasses.replace(job, out_dir=str(tmp))
    started, t0 = now(), time.perf_counter()
    scratch = _scratch(tmp)
    message = {"job": job.to_json(), "id": tmp.name, "timeout_s": timeout_s, "parent": os.getpid(),
               "crash": faults.crash_for(job), "scratch": scratch}  # each start adds "dispatch_wall" as it hands the run over
    try:
        if start == "fork":
            status = _run_forked(message, timeout_s)
        elif start == "spawn":
            status = _run_spawned(message, tmp, timeout_s)
        else:
            status = _run_here(message, timeout_s, poll, every_s)
    finally:  # the child's temporary files (SUMO's SSM output, rewritten route files) go even when it was killed
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    res = outcome_of(tmp, status, timeout_s)
    return dataclasses.replace(res, started_at=started, ended_at=now(), wall_s=time.perf_counter() - t0, start=start,
                               clock_s=dict(res.clock_s, ended_wall=time.time()))


def _scratch(tmp: pathlib.Path) -> str | None:
    """A fresh folder for the child's temporary files inside the run's own folder, removed by the parent once the
    child has ended (a child killed by a signal or a timeout cannot clean up after itself; a killed batch's
    partial run folders, and so this, go when it resumes: studies.pools.discard_unrecorded); None (the system's
    default) if none can be made. (In the system's temp folder, every batch killed mid-run left one there.)"""
    try:
        path = tmp / ".scratch"
        path.mkdir()
        return str(path)
    except OSError:
        return None


def outcome_of(tmp: pathlib.Path, status: dict, timeout_s: float) -> RunOutcome:
    """The run's outcome: its result.json, or the failure its exit status tells."""
    res_file = tmp / "result.json"
    rc, timed_out = status.get("rc"), status.get("timed_out", False)
    if res_file.is_file() and not timed_out:
        res = RunOutcome.from_json(json.loads(res_file.read_text()))
    elif timed_out:
        res = RunOutcome("timeout", error=f"timeout: run exceeded {timeout_s:g} s and was killed")
    elif status.get("error"):
        res = RunOutcome("crashed", error=status["error"])
    elif UNWRITABLE_RC < rc < 256:  # the child could not write its folder at all (runs.child.exit_unwritable)
        gone = from_errno(rc - UNWRITABLE_RC, tmp)
        res = RunOutcome("failed", error=str(gone), unwritable=[gone.path, gone.reason])
    elif rc < 0:
        res = RunOutcome("crashed", error=f"worker died: {_signal_name(-rc)}", where=crash_site(tmp / "stderr.txt") or None)
    else:
        tail = _last_line(tmp / "stderr.txt")
        res = RunOutcome("crashed", error=f"worker exited with code {rc} and no result" + (f": {tail}" if tail else ""))
    clock = dict(res.clock_s, **{k: v for k, v in status.items() if k.endswith("_wall")})
    overhead = clock["sumo_start_wall"] - clock["dispatch_wall"] if "sumo_start_wall" in clock else None
    return dataclasses.replace(res, clock_s=clock, overhead_s=overhead)


def _run_spawned(message: dict, tmp: pathlib.Path, timeout_s: float) -> dict:
    message["dispatch_wall"] = time.time()
    with open(tmp / "stdout.txt", "wb") as out, open(tmp / "stderr.txt", "wb") as err:
        proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.runs.child", json.dumps(message)],
                                stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=_child_env())
        with _LIVE_LOCK:
            _LIVE.add(proc)
        try:
            rc = proc.wait(timeout=None if math.isinf(timeout_s) else timeout_s)
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
    return {"rc": rc, "timed_out": timed_out, "dispatch_wall": message["dispatch_wall"], "reaped_wall": time.time()}


def _run_here(message: dict, timeout_s: float, poll, every_s: float) -> dict:
    """A child forked from this (single-threaded) process; ``poll()`` every ``every_s`` while it runs."""
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    message["dispatch_wall"] = time.time()
    deadline = time.monotonic() + timeout_s
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child's own process
        enter(message)
    timed_out = False
    try:
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            if time.monotonic() >= deadline and not timed_out:
                os.kill(pid, signal.SIGKILL)
                timed_out = True
            if poll is not None:
                poll()
            time.sleep(every_s)
    except BaseException:  # Ctrl-C: the child goes too
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        raise
    if poll is not None:
        poll()
    return {"rc": os.waitstatus_to_exitcode(status), "timed_out": timed_out, "dispatch_wall": message["dispatch_wall"],
            "reaped_wall": time.time()}


class _Server:
    """Parent side of one fork server: writes dispatch messages to its stdin, a reader thread hands the replies
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

    def submit(self, message: dict) -> list | None:
        """Hand a run over; None if the server is gone."""
        waiter = [threading.Event(), None]
        with self.lock:
            if self.dead is not None:
                return None
            self.waiting[message["id"]] = waiter
            try:
                self.proc.stdin.write(json.dumps(message).encode() + b"\n")
                self.proc.stdin.flush()
            except (BrokenPipeError, ValueError):  # died (or was closed) since: the reader will notice
                self.waiting.pop(message["id"], None)
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


def _run_forked(message: dict, timeout_s: float) -> dict:
    message["dispatch_wall"] = dispatched = time.time()
    server = _server()
    waiter = server.submit(message)
    if waiter is None:  # it died between runs (e.g. killed by hand): one fresh start, then give up
        server = _server()
        waiter = server.submit(message)
    if waiter is None:
        return {"error": f"worker died: the fork server {server.dead}", "dispatch_wall": dispatched}
    if not waiter[0].wait(None if math.isinf(timeout_s) else timeout_s + SERVER_GRACE_S):  # the server itself hangs: nothing else can stop the run
        server.kill()
        return {"timed_out": True, "dispatch_wall": dispatched}
    reply = waiter[1]
    if reply is None:
        return {"error": f"worker died: the fork server {server.dead}", "dispatch_wall": dispatched}
    reply["notified_wall"] = time.time()
    reply["dispatch_wall"] = dispatched
    return reply
