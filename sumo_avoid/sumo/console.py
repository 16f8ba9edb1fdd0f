"""SUMO's own messages during a run: into ``sumo.log`` only, and a one-line count afterwards.

With ``--log FILE`` SUMO writes every message to FILE *and* its warnings and errors to the
process's stderr (file descriptor 2, from C++, beside Python): a run in dense traffic fills the
terminal with thousands of "emergency braking" lines. :func:`sumo_console_to` points descriptor 2
at a file for the run while Python's own ``sys.stderr`` (progress bar, Python warnings) keeps
writing to the terminal; :func:`leftover` is what SUMO wrote there that the log does not hold.
"""
from __future__ import annotations

import contextlib
import os
import pathlib
import sys
import tempfile


@contextlib.contextmanager
def sumo_console_to(path: pathlib.Path):
    """Inside the block, what native code writes to descriptor 2 goes to ``path``; ``sys.stderr``
    writes to the terminal still (when it was descriptor 2; a redirected ``sys.stderr`` is kept)."""
    try:
        swap = sys.stderr.fileno() == 2
    except (AttributeError, OSError, ValueError):  # e.g. a StringIO under test
        swap = False
    sys.stderr.flush()
    saved = os.dup(2)
    with open(path, "wb") as fh:
        os.dup2(fh.fileno(), 2)
    python_stderr = sys.stderr
    if swap:
        sys.stderr = open(os.dup(saved), "w", buffering=1, encoding=python_stderr.encoding,
                          errors=python_stderr.errors)
    try:
        yield
    finally:
        if swap:
            sys.stderr.close()
            sys.stderr = python_stderr
        os.dup2(saved, 2)
        os.close(saved)


@contextlib.contextmanager
def native_stderr_kept():
    """Inside the block, what native code writes to descriptor 2 (SUMO's errors while it loads its
    files: libsumo's exception says only "Process Error") is kept as well: the yielded list holds the
    text afterwards, and the text is passed on to descriptor 2 as if nothing had come between."""
    said: list[str] = []
    try:
        keep = tempfile.TemporaryFile()
    except OSError:  # nowhere to keep it (a full disk): SUMO writes to descriptor 2 as ever
        yield said
        return
    with keep:
        sys.stderr.flush()
        saved = os.dup(2)
        os.dup2(keep.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            keep.seek(0)
            text = keep.read()
            with contextlib.suppress(OSError):
                _write_all(2, text)
            said.append(text.decode(errors="replace"))


def _write_all(fd: int, data: bytes) -> None:
    while data:
        data = data[os.write(fd, data):]


def first_error(text: str) -> str:
    """SUMO's first ``Error: ...`` line in ``text``, without the prefix ("" if none)."""
    for line in text.splitlines():
        if line.startswith("Error: "):
            return line[len("Error: "):].strip()
    return ""


def count(log_file: pathlib.Path, kind: str = "Warning") -> int:
    """How many messages of ``kind`` ("Warning", "Error") SUMO wrote to its log."""
    try:
        text = pathlib.Path(log_file).read_text(errors="replace")
    except OSError:
        return 0
    return sum(1 for line in text.splitlines() if line.startswith(f"{kind}: "))


def summary_line(log_file: pathlib.Path, name: str = "sumo.log") -> str:
    """``sumo.log: 12 warnings`` (and errors, if any)."""
    w, e = count(log_file, "Warning"), count(log_file, "Error")
    parts = [f"{w} warning{'' if w == 1 else 's'}"] + ([f"{e} error{'' if e == 1 else 's'}"] if e else [])
    return f"{name}: {', '.join(parts)}"


def leftover(console_file: pathlib.Path, log_file: pathlib.Path) -> list[str]:
    """Lines written to descriptor 2 during the run that are not in the log (not SUMO's messages)."""
    try:
        text = pathlib.Path(console_file).read_text(errors="replace")
        logged = set(pathlib.Path(log_file).read_text(errors="replace").splitlines())
    except OSError:
        return []
    return [line for line in text.splitlines() if line.strip() and line not in logged]


def start_error(first: str, libsumo_says: str) -> str:
    """Why SUMO would not start: its first error line, and libsumo's message where that says more."""
    if not first or libsumo_says in (first, "", "Process Error"):
        return first or libsumo_says
    return f"{first}; {libsumo_says}"
