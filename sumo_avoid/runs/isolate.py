"""One run in a child forked from this very process (``sumo-avoid run``): the batch's worker run
(:func:`sumo_avoid.runs.worker.child`: result.json, artifacts in a private folder), without a
fork server, so the child starts with this process's imports (a fork server would import
everything a second time, ~2.5 s). A SIGSEGV or abort inside SUMO kills only the child; the
parent reads its exit status like the batch does (:func:`sumo_avoid.runs.worker.run_in`).
"""
from __future__ import annotations

import math
import os
import pathlib
import signal
import sys
import time
import traceback

from sumo_avoid.runs import worker
from sumo_avoid.runs.watch import own_stdio


def run_forked(tmp: pathlib.Path, spec: dict, poll=None, every_s: float = 0.2) -> dict:
    """Run ``spec`` (RunSpec.to_json() fields) in a forked child with ``tmp`` as its folder; call
    ``poll()`` every ``every_s`` while it runs. Returns the result dict (never raises for a failed run;
    an interrupt kills the child and is raised)."""
    tmp = pathlib.Path(tmp).absolute()
    job = dict(spec, out=str(tmp), timeout_s=math.inf, id=tmp.name, parent=os.getpid(), dispatch_wall=time.time())
    started, t0 = worker.now(), time.perf_counter()
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child's own process
        _child(job)
    try:
        while True:
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                break
            if poll is not None:
                poll()
            time.sleep(every_s)
    except BaseException:  # Ctrl-C: the child goes too
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        raise
    if poll is not None:
        poll()
    res = worker.result_of(tmp, {"rc": os.waitstatus_to_exitcode(status), "dispatch_wall": job["dispatch_wall"],
                                 "reaped_wall": time.time()}, math.inf)
    res.update(started_at=started, ended_at=worker.now(), wall_s=time.perf_counter() - t0, start="fork")
    return res


def _child(job: dict) -> None:  # pragma: no cover - runs in the child
    """The forked child: its own stdio files in its folder, the run, exit (never returns)."""
    rc = 1
    try:
        own_stdio(pathlib.Path(job["out"]))
        rc = worker.child(job)
    except BaseException:  # whatever it was, the parent reads the exit status and stderr.txt
        os.write(2, traceback.format_exc().encode())
    finally:
        worker.exit_now(rc)
