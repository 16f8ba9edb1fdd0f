"""Output folders that fail, for the unwritable-output tests (issue 35): a full disk, a read-only
folder, a folder that vanishes while a command runs.

* Full disk, two ways: a file-size limit (``RLIMIT_FSIZE``) on the command's process and everything
  it starts, with SIGXFSZ ignored so that a write past the limit fails with EFBIG ("File too large")
  instead of killing the process (any Linux, any user); or a small tmpfs filled to the last byte
  (ENOSPC, "No space left on device"; needs ``mount``, i.e. root or CAP_SYS_ADMIN).
* Read-only: a tmpfs remounted read-only (root ignores file permissions, so chmod proves nothing).
* Vanished: a thread removes the folder as soon as the command has made it.

A test whose mechanism is not available here is skipped with the reason.
"""
from __future__ import annotations

import dataclasses
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import threading
import time

import matplotlib.font_manager  # noqa: F401 - matplotlib's font cache made here, not by a command under a limit
import pytest


def fsize_limit(limit: int):
    """A ``preexec_fn``: every file the process (and its children) writes is capped at ``limit`` bytes."""
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        pytest.skip("no resource module: RLIMIT_FSIZE is needed for a full disk without mount")

    def limit_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return limit_files


def cli(*argv, cwd: pathlib.Path, fsize: int | None = None, during=None, timeout: float = 300.0):
    """``sumo-avoid ARGV`` in a process of its own (with a file-size limit; ``during()`` in a thread
    while it runs). Returns the CompletedProcess-like (returncode, stdout, stderr)."""
    proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.cli", *map(str, argv)], cwd=cwd, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            preexec_fn=fsize_limit(fsize) if fsize else None)
    thread = threading.Thread(target=during, daemon=True) if during else None
    if thread:
        thread.start()
    out, err = proc.communicate(timeout=timeout)
    if thread:
        thread.join(timeout)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def when_made(path: pathlib.Path, action, timeout: float = 120.0):
    """For ``cli(during=...)``: ``action()`` as soon as ``path`` exists."""
    def watch():
        end = time.monotonic() + timeout
        while not path.exists() and time.monotonic() < end:
            time.sleep(0.002)
        action()
    return watch


def remove(folder: pathlib.Path):
    """An action: remove ``folder`` and everything in it (again while the command writes into it)."""
    def rm():
        for _ in range(100):
            shutil.rmtree(folder, ignore_errors=True)
            if not folder.exists():
                return
            time.sleep(0.01)
    return rm


@dataclasses.dataclass
class Tmpfs:
    path: pathlib.Path

    def read_only(self) -> None:
        subprocess.run(["mount", "-o", "remount,ro", str(self.path)], check=True, capture_output=True)

    def fill(self) -> None:
        """Write a filler file until the file system is full (ENOSPC)."""
        with open(self.path / "filler", "wb", buffering=0) as f:
            for size in (1 << 16, 1 << 12, 1 << 9, 1):
                try:
                    while True:
                        f.write(b"\0" * size)
                except OSError:
                    pass
        assert os.statvfs(self.path).f_bavail == 0


@pytest.fixture
def tmpfs(tmp_path):
    """A 2 MiB tmpfs at ``tmp_path/disk``, unmounted afterwards; skipped where mount is not permitted."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    try:
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mnt)], capture_output=True, text=True)
    except OSError as e:
        pytest.skip(f"no mount program here ({e}): a tmpfs is needed for this case")
    if r.returncode != 0:
        pytest.skip(f"mount -t tmpfs is not permitted here (needs root or CAP_SYS_ADMIN): {r.stderr.strip()}")
    try:
        yield Tmpfs(mnt)
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def one_line(r, *names) -> str:
    """Exit code 2, exactly one stderr line, no traceback, naming every one of ``names``."""
    assert "Traceback" not in r.stderr, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("sumo-avoid: error: "), lines[0]
    for n in names:
        assert str(n) in lines[0], (n, lines[0])
    assert r.returncode == 2, (r.returncode, r.stderr)
    return lines[0]


def files_under(folder: pathlib.Path) -> list[str]:
    """Every file under ``folder``, relative, sorted ([] if it does not exist)."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file()) if folder.exists() else []
