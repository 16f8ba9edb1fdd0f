"""The fork server's own side (``python -m sumo_avoid.runs.forkserver PARENT_PID``).

It imports what every run needs once, then forks one fresh child per job line on stdin, enforces
each run's timeout (pidfd, race-free kill) and replies one JSON line per finished child on stdout.
It never runs a simulation itself. The parent side (``_Server``, ``run_in``) lives in
:mod:`sumo_avoid.runs.worker`, which documents the whole scheme, the run itself in
:mod:`sumo_avoid.runs.child`.
"""
from __future__ import annotations

import json
import os
import select
import signal
import sys
import time

from sumo_avoid.runs.child import enter
from sumo_avoid.sensing import occlusion


def serve(parent: int) -> int:
    """Fork one child per message line on stdin; reply one JSON line per finished child on stdout.

    Exits (killing its running children) on EOF on stdin or when ``parent`` is gone.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the batch process kills us (and ours)
    t0 = time.perf_counter()
    # what every run needs, plots included, came with this module's imports (child -> outputs,
    # runner, plots); the radar's compiled kernel is loaded now (numba, from its on-disk cache)
    occlusion.warm()

    def reply(msg: dict) -> None:
        os.write(1, json.dumps(msg).encode() + b"\n")

    threads = len(os.listdir("/proc/self/task"))
    if threads > 1:
        print(f"sumo_avoid.runs.forkserver: fork server has {threads} threads after its imports; forking it is unsafe",
              file=sys.stderr)
    reply({"pid": os.getpid(), "import_s": time.perf_counter() - t0, "threads": threads})
    running: dict[int, dict] = {}  # pidfd -> {"pid", "id", "deadline", "timed_out", "fork_wall"}
    poller = select.poll()
    poller.register(0, select.POLLIN)
    buf = b""
    try:
        while True:
            now = time.monotonic()
            wait_s = min([1.0] + [r["deadline"] - now for r in running.values()])
            for fd, _ in poller.poll(max(0.0, wait_s) * 1000):
                if fd != 0:
                    poller.unregister(fd)
                    r = running.pop(fd)
                    os.close(fd)
                    _, status = os.waitpid(r["pid"], 0)
                    reply({"id": r["id"], "rc": os.waitstatus_to_exitcode(status), "timed_out": r["timed_out"],
                           "fork_wall": r["fork_wall"], "reaped_wall": time.time()})
                    continue
                data = os.read(0, 1 << 16)
                if not data:
                    return 0
                buf += data
                while b"\n" in buf:
                    line, buf = buf.split(b"\n", 1)
                    msg = json.loads(line)
                    msg["parent"] = os.getpid()
                    fork_wall = time.time()
                    try:
                        pid = os.fork()
                    except OSError as e:
                        reply({"id": msg["id"], "error": f"worker could not start: fork failed: {e}"})
                        continue
                    if pid == 0:  # SIGINT stays ignored: on Ctrl-C the batch kills the server and so its children
                        enter(msg, list(running))
                    pidfd = os.pidfd_open(pid)
                    running[pidfd] = {"pid": pid, "id": msg["id"], "deadline": time.monotonic() + msg["timeout_s"],
                                      "timed_out": False, "fork_wall": fork_wall}
                    poller.register(pidfd, select.POLLIN)
            now = time.monotonic()
            for fd, r in running.items():
                if not r["timed_out"] and now >= r["deadline"]:
                    signal.pidfd_send_signal(fd, signal.SIGKILL)
                    r["timed_out"] = True
            if os.getppid() != parent:
                return 0
    except BrokenPipeError:  # the parent is gone
        return 0
    finally:
        for fd in running:
            signal.pidfd_send_signal(fd, signal.SIGKILL)


if __name__ == "__main__":
    os._exit(serve(int(sys.argv[1])))  # nothing to flush (replies are os.write): skip the 0.25 s teardown
