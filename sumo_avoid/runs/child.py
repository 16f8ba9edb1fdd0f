"""The run itself, in its own fresh process: load the scenario, roll out, write the results.

Every way of starting the process (:mod:`sumo_avoid.runs.worker`: forked from the fork server,
forked from the caller, or a fresh ``python -m sumo_avoid.runs.child MESSAGE`` interpreter) ends in
:func:`run` with the dispatch message: ``{"job": RunJob.to_json(), "id", "parent", "timeout_s",
"dispatch_wall", "crash"}`` (``crash``: test-only fault injection, :mod:`sumo_avoid.runs.faults`).
The child writes its artifacts into the job's ``out_dir`` and, last, ``result.json`` (its part of
the :class:`~sumo_avoid.runs.job.RunOutcome`, atomically); a child that dies writes nothing, and the
parent builds the outcome from its exit status.
"""
from __future__ import annotations

import os
import time

_IMPORT_START = (os.getpid(), time.time())  # a spawned run's interpreter imports what follows itself

import dataclasses  # noqa: E402
import faulthandler  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import pathlib  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import traceback  # noqa: E402

from sumo_avoid.core.config import ScenarioError  # noqa: E402
from sumo_avoid.core.output_error import OutputError, writing  # noqa: E402
from sumo_avoid.runs import outputs, runner  # noqa: E402
from sumo_avoid.runs.faults import CRASH_AT_S, CrashAt, crash  # noqa: E402
from sumo_avoid.runs.job import SCENARIO, UNWRITABLE_RC, RunJob, RunOutcome  # noqa: E402
from sumo_avoid.runs.watch import ProgressFile, cpu_s, die_with_parent, own_stdio  # noqa: E402
from sumo_avoid.scenario import spec as scenario  # noqa: E402

_IMPORTED = time.time()


def exit_now(rc: int) -> None:
    """Flush stdio and exit without the interpreter's teardown: nothing in it is needed once
    result.json is written, and freeing pandas, numpy, libsumo... is most of a child's time from
    its result to being reaped."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:
            pass
    os._exit(rc)


def exit_unwritable(e: OSError) -> None:
    """Exit with :data:`~sumo_avoid.runs.job.UNWRITABLE_RC` + the error's errno: the run's folder cannot
    be written, so the exit code is the only way left to tell the parent why."""
    exit_now(UNWRITABLE_RC + e.errno if e.errno and e.errno < 256 - UNWRITABLE_RC else 1)


def enter(message: dict, inherited_fds=()) -> None:
    """A freshly forked child: close the parent's ``inherited_fds``, own stdio files in the job's
    folder, the run, exit (never returns)."""
    rc = 1
    try:
        for fd in inherited_fds:
            os.close(fd)
        try:
            own_stdio(pathlib.Path(message["job"]["out_dir"]))
        except OSError as e:  # its folder is gone or cannot be written: nothing to say on the parent's stderr
            exit_unwritable(e)
        rc = run(message)
    except BaseException:  # whatever it was, the parent reads the exit status and stderr.txt (fd 2: sys.stderr
        os.write(2, traceback.format_exc().encode())  # may be a caller's replacement, e.g. a test's capture)
    finally:
        exit_now(rc)


def _kind_function(kind: str):
    """The ``"package.module:function"`` a job of this kind calls after its rollout."""
    module, _, name = kind.partition(":")
    return getattr(importlib.import_module(module), name)


def run(message: dict) -> int:
    """Run the message's job in this process; write result.json; return the exit code."""
    own_imports = _IMPORT_START[0] == os.getpid()  # spawned: this process imported the run's modules
    marks = {"entry_wall": _IMPORT_START[1] if own_imports else time.time()}
    faulthandler.enable(file=2)  # a fatal signal writes the Python stack to stderr.txt: where the run died
    die_with_parent()
    if os.getppid() != message["parent"]:  # the parent died before prctl took effect
        return 3
    if message.get("scratch"):  # the parent removes it after this process, however it ends
        tempfile.tempdir = message["scratch"]
    job = RunJob.from_json(message["job"])
    out = pathlib.Path(job.out_dir)

    def finish(outcome: RunOutcome) -> None:
        part = out / "result.json.part"
        try:
            part.write_text(json.dumps(dataclasses.replace(outcome, clock_s=marks).to_json(), sort_keys=True))
            os.replace(part, out / "result.json")
        except OSError as e:  # not even the result can be written: the exit code tells why
            exit_unwritable(e)

    try:
        marks["imported_wall"] = _IMPORTED if own_imports else time.time()
        scn = scenario.load(job.scenario, list(job.overrides), controller=job.controller, seed=job.seed)
        after_run = None if job.kind == SCENARIO else _kind_function(job.kind)  # found before SUMO starts
        marks["loaded_wall"] = time.time()
        kind = message.get("crash")
        if kind in ("segfault", "abort"):
            crash(kind)
        t_run = time.time()
        watch = [ProgressFile(str(out / "progress"))] if job.progress else []
        if kind == "segfault_mid_run":
            watch.append(CrashAt(CRASH_AT_S))
        res = runner.run(scn, log_file=out / "sumo.log", progress=False, callbacks=watch)
        marks["sumo_start_wall"] = t_run + res.timings.get("setup_s", 0.0)  # road and controllers set up
        marks["run_end_wall"] = time.time()
        if after_run is None:
            m = outputs.write_outputs(res, out, plots=scn.spec.output.plots and job.plots)
        else:
            with writing(out):
                m = after_run(res, job, out)
        marks["written_wall"] = time.time()
        finish(RunOutcome("done", metrics=m, timings_s=res.timings, cpu_s=cpu_s()))
        return 0
    except OutputError as e:  # a file of the run cannot be written: the caller stops, one line
        finish(RunOutcome("failed", error=str(e)[:500], unwritable=[e.path, e.reason]))
        return 1
    except ScenarioError as e:  # bad input found only once SUMO ran: the caller reports it as such
        finish(RunOutcome("failed", error=f"ScenarioError: {e}"[:500], bad_input=str(e)))
        return 1
    except Exception as e:  # recorded as the run's failure, one line
        msg = str(e).strip().splitlines()[0] if str(e).strip() else ""
        finish(RunOutcome("failed", error=f"{type(e).__name__}: {msg}"[:500]))
        return 1


if __name__ == "__main__":
    exit_now(run(json.loads(sys.argv[1])))
