"""An output that cannot be written (a full disk, a read-only or vanished folder) as one error:
:class:`OutputError`, the path and the operating system's reason. The command line prints it as one
line, ``sumo-avoid: error: cannot write PATH: REASON``, and exits with code 2 (docs/errors.md).

Writes are turned into it where they happen, in a few places: the atomic write of a command's
files (``studies/files.write_atomic``), a run's files (``runs/outputs.py``, in the run's process),
the moves and records of a run's folder (``runs/worker.py``, ``cli.py``) and the ledger
(``studies/ledger.py``, ``studies/batch.py``): :func:`writing` around them.
"""
from __future__ import annotations

import contextlib
import errno
import os
import pathlib
import sqlite3


class OutputError(OSError):
    """``path`` cannot be written; ``reason`` is the operating system's (or SQLite's) word for why."""

    def __init__(self, path, reason: str):
        self.path, self.reason = str(path), reason
        super().__init__(f"cannot write {self.path}: {reason}")

    def __str__(self) -> str:
        return self.args[0]

    def __reduce__(self):  # picklable: it may cross a process (a Dask worker)
        return OutputError, (self.path, self.reason)


def reason(e: BaseException) -> str:
    """The operating system's reason in ``e`` (``No space left on device``), or its message."""
    if isinstance(e, OSError) and e.errno is not None:
        return e.strerror or os.strerror(e.errno)
    return " ".join(str(e).split()) or type(e).__name__


def from_os(e: BaseException, path) -> OutputError:
    """``e`` (an OSError or a SQLite error) as an OutputError naming the file the OS names as the
    target (a copy's or rename's destination, an open's file), else ``path``."""
    if isinstance(e, OutputError):
        return e
    if isinstance(e, sqlite3.OperationalError) and not pathlib.Path(path).exists():  # SQLite says "disk I/O error"
        return vanished(path)
    named = (getattr(e, "filename2", None) or getattr(e, "filename", None)) if isinstance(e, OSError) else None
    return OutputError(named if isinstance(named, (str, pathlib.PurePath)) else path, reason(e))


def from_errno(code: int, path) -> OutputError:
    return OutputError(path, os.strerror(code))


@contextlib.contextmanager
def writing(path, discard: bool = False):
    """Inside the block, an OSError or a SQLite error is raised as an :class:`OutputError` (:func:`from_os`);
    ``discard``: the file ``path`` is removed then (nothing half-written is left)."""
    try:
        yield
    except (OSError, sqlite3.OperationalError) as e:  # SQLite's full disk, read-only file, I/O error
        if discard:
            with contextlib.suppress(OSError):
                pathlib.Path(path).unlink()
        raise from_os(e, path) from None


def vanished(path) -> OutputError:
    """``path`` (a file being written) is gone from its folder."""
    return from_errno(errno.ENOENT, path)
