"""The run's side of a worker process besides the run itself: its own stdio, dying with the parent,
its CPU time, the simulated time for the parent's progress bar (:class:`ProgressFile`), and where a
run that died by a signal died (:func:`crash_site`, from faulthandler's stack in its stderr).
"""
from __future__ import annotations

import os
import pathlib
import re
import signal
import time

def own_stdio(out: pathlib.Path) -> None:
    """A fresh child's stdin from /dev/null, stdout and stderr into ``out``/stdout.txt, stderr.txt
    (file descriptors 0-2: native code, SUMO, writes there too)."""
    for fd, (path, flags) in enumerate([(os.devnull, os.O_RDONLY),
                                        (out / "stdout.txt", os.O_WRONLY | os.O_CREAT | os.O_TRUNC),
                                        (out / "stderr.txt", os.O_WRONLY | os.O_CREAT | os.O_TRUNC)]):
        f = os.open(path, flags, 0o644)
        os.dup2(f, fd)
        os.close(f)


def die_with_parent() -> None:
    """Linux: get SIGKILL when the parent dies, so a killed batch leaves no orphan runs."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - not Linux
        pass


def cpu_s() -> float | None:
    """CPU time of this process so far (a forked child's count starts at 0)."""
    try:
        import resource
    except ImportError:  # pragma: no cover - Windows
        return None
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def crash_site(stderr_file: pathlib.Path) -> str:
    """The innermost Python frame faulthandler wrote when the child died by a signal, e.g.
    ``libsumo/libsumo.py:3545 (start)`` ("" if none)."""
    try:
        text = stderr_file.read_text(errors="replace")
    except OSError:
        return ""
    m = re.search(r'File "([^"]+)", line (\d+) in (\S+)', text.split("most recent call first", 1)[-1])
    if not m:
        return ""
    path = m.group(1)
    for root in ("/site-packages/", "/sumo_avoid/"):  # libsumo/libsumo.py, sumo_avoid/sumo/sim.py
        if root in path:
            path = ("sumo_avoid/" if root == "/sumo_avoid/" else "") + path.rsplit(root, 1)[-1]
            break
    return f"{path}:{m.group(2)} ({m.group(3)})"


class ProgressFile:
    """Rollout callback: the simulated time written to a file (a fixed-width number, rewritten in
    place at most every 0.2 s), for a parent process's progress bar."""

    def __init__(self, path: str):
        self.fd, self.last, self.time_s = os.open(path, os.O_WRONLY | os.O_CREAT, 0o644), 0.0, 0.0

    def on_step(self, snap, n_steps: int) -> None:
        self.time_s = snap.time_s
        if time.monotonic() - self.last >= 0.2:
            self.last = time.monotonic()
            self._write()

    def _write(self) -> None:
        os.pwrite(self.fd, f"{self.time_s:16.3f}".encode(), 0)

    def on_end(self) -> None:
        self._write()
        os.close(self.fd)
