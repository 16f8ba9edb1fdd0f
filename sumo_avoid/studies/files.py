"""The batch and suite file formats, as frozen dataclasses validated by :func:`core.config.build`,
the same mechanism as scenario files (one error form: file, dotted key, what was expected).

Also the checks of output paths (a folder made before the runs, a file path that can be written
after them) and atomic writes. Seeds are kept as written (``"1-20"``, ``7`` or ``[1, 3]``) and expanded by
:func:`sumo_avoid.studies.batch.parse_seeds`; paths are relative to the file that names them.
"""
from __future__ import annotations

import contextlib
import errno
import os
import pathlib
from dataclasses import dataclass

from sumo_avoid.core.config import FieldError, ScenarioError, field_doc
from sumo_avoid.core.output_error import OutputError, reason

Seeds = str | int | tuple[int, ...]


@dataclass(frozen=True)
class BatchRuns:
    """One ``[[runs]]`` table: a scenario x seeds x controllers x grid points."""

    scenario: str = field_doc(nonempty=True, doc="scenario file, relative to the batch file")
    seeds: Seeds = field_doc(doc='seeds: "1-20", "1,3,7" or a list of integers')
    set: tuple[str, ...] = field_doc((), doc="KEY=VALUE overrides for every run of this table")
    controllers: tuple[str, ...] = field_doc((), doc="one run per controller (default: the scenario's)")
    grid: dict = field_doc(default_factory=dict, doc="dotted key -> list of values; one run per combination")

    def __post_init__(self):
        for k, v in self.grid.items():
            if not isinstance(v, list) or not v:
                raise FieldError(f"grid.{k}", "a non-empty list of values", v)


@dataclass(frozen=True)
class BatchFile:
    """A batch TOML file."""

    runs: tuple[BatchRuns, ...] = field_doc(nonempty=True, doc="[[runs]] tables")
    workers: int | None = field_doc(None, positive=True, doc="parallel runs (default: number of cores)")
    timeout_s: float | None = field_doc(None, positive=True, doc="per-run timeout, s (default 600)")
    ledger: str | None = field_doc(None, nonempty=True, doc="SQLite ledger, relative to the batch file")


@dataclass(frozen=True)
class SuiteDefaults:
    """``[defaults]`` of a suite file: seeds and overrides for every entry."""

    seeds: Seeds | None = field_doc(None, doc="seeds of every entry that names none")
    set: tuple[str, ...] = field_doc((), doc="KEY=VALUE overrides put before each entry's own")


@dataclass(frozen=True)
class SuiteEntry:
    """One ``[[entry]]`` of a suite: a scenario, a controller, seeds and pass criteria."""

    name: str = field_doc(nonempty=True, doc="entry name, unique in the suite")
    scenario: str = field_doc(nonempty=True, doc="scenario file, relative to the suite file")
    criteria: tuple[str, ...] = field_doc(nonempty=True, doc="criteria like 'collisions == 0'")
    controller: str | None = field_doc(None, doc="controller (default: the scenario's)")
    seeds: Seeds | None = field_doc(None, doc="seeds (default: [defaults].seeds)")
    set: tuple[str, ...] = field_doc((), doc="KEY=VALUE overrides")


@dataclass(frozen=True)
class SuiteFile:
    """A suite TOML file."""

    entry: tuple[SuiteEntry, ...] = field_doc(nonempty=True, doc="[[entry]] tables")
    defaults: SuiteDefaults = field_doc(default_factory=SuiteDefaults, doc="[defaults]")

    def __post_init__(self):
        seen = set()
        for i, e in enumerate(self.entry):
            if e.name in seen:
                raise FieldError(f"entry[{i}].name", "a name not used by another entry", e.name)
            seen.add(e.name)


# --- output paths: checked before any run starts, written atomically ---------------------------------
CL = "<command line>"


#: the files a finished run leaves in its folder (runs/outputs.py: metrics; cli.cmd_run: a crash's record)
RUN_RECORDS = ("metrics.json", "failed.json")


def refuse_finished_run(path, flag: str) -> None:
    """Raise ScenarioError naming ``flag`` if the folder ``path`` already holds a finished run (its metrics or
    its failure record): a second run into it would rewrite the first one's files."""
    path = pathlib.Path(path)
    found = [f for f in RUN_RECORDS if (path / f).is_file()]
    if found:
        raise ScenarioError(CL, flag, f"a folder that holds no finished run (this one holds {found[0]}: give "
                            "another one, or remove it)", str(path))


def make_dirs(path, flag: str) -> list[pathlib.Path]:
    """Create the output folder ``path`` (and its missing parents) now, before anything runs; return
    the folders created, for :func:`remove_dirs` if the command then fails. Raises ScenarioError
    naming ``flag`` if ``path`` is a file, lies under a file or cannot be created."""
    path = pathlib.Path(path)
    if path.exists() and not path.is_dir():
        raise ScenarioError(CL, flag, "a folder (this is a file)", str(path))
    missing, p = [], path.absolute()
    while not p.exists():
        missing.append(p)
        p = p.parent
    if not p.is_dir():
        raise ScenarioError(CL, flag, f"a folder path ({p} is a file)", str(path))
    made: list[pathlib.Path] = []
    try:
        for d in reversed(missing):
            d.mkdir()
            made.append(d)
    except OSError as e:
        remove_dirs(made)
        raise ScenarioError(CL, flag, f"a folder that can be created ({e.strerror})", str(path)) from None
    if not os.access(path, os.W_OK | os.X_OK):
        remove_dirs(made)
        raise ScenarioError(CL, flag, f"a folder this user can write ({_not_writable(path)})", str(path))
    return made


def remove_dirs(made) -> None:
    """Remove the folders :func:`make_dirs` created, deepest first, those still empty."""
    for d in reversed(list(made)):
        with contextlib.suppress(OSError):
            d.rmdir()


def check_out_file(path, flag: str) -> None:
    """A file to be written later (after the runs): not a folder, and under a folder that exists or
    can be created (no file on the way). Raises ScenarioError naming ``flag``."""
    path = pathlib.Path(path)
    if path.is_dir():
        raise ScenarioError(CL, flag, "a file path, not a folder", str(path))
    p = path.absolute().parent
    while not p.exists():
        p = p.parent
    if not p.is_dir():
        raise ScenarioError(CL, flag, f"a path under a folder ({p} is a file)", str(path))
    if not os.access(p, os.W_OK | os.X_OK):
        raise ScenarioError(CL, flag, f"a path this user can write ({p}: {_not_writable(p)})", str(path))


def _not_writable(folder) -> str:
    """The operating system's reason a folder ``os.access`` finds not writable (it may have vanished
    since it was made or found)."""
    if not os.path.isdir(folder):
        return os.strerror(errno.ENOENT)
    try:
        read_only = bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except OSError:
        read_only = False
    return os.strerror(errno.EROFS if read_only else errno.EACCES)


def write_atomic(path, data: str | bytes) -> None:
    """Write a file whole or not at all: a temporary file beside it, then renamed over it. Its folder
    must exist (:func:`make_dirs` makes a command's folders when it starts; a folder that vanished since
    is not made again). Raises OutputError naming ``path`` if it cannot be written (a full disk, a
    read-only or vanished folder)."""
    path = pathlib.Path(path)
    part = path.with_name(f".{path.name}.{os.getpid()}.part")
    try:
        if isinstance(data, bytes):
            part.write_bytes(data)
        else:
            part.write_text(data)
        os.replace(part, path)
    except OSError as e:
        raise OutputError(path, reason(e)) from None
    finally:
        with contextlib.suppress(OSError):
            part.unlink()
