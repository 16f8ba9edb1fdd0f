"""The results ledger: one SQLite file, table ``runs``, one row per run key.

Only the batch's parent process writes it (workers return their results), one transaction per
finished run, in WAL mode, so a killed batch leaves every committed row intact and nothing
half-written. A row with ``status = 'done'`` is never rewritten: :func:`record` upserts only over
a missing or ``failed`` row. Scalar metrics become columns (added on first sight); lists and
nested values stay in the run's ``metrics.json`` in its artifacts folder.

Read it with ``pandas.read_sql("SELECT * FROM runs", sqlite3.connect(path))`` or :func:`read`.
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import io
import json
import os
import pathlib
import re
import sqlite3
from importlib import metadata

import pandas as pd

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.core.output_error import vanished, writing
from sumo_avoid.studies.files import CL, check_out_file, write_atomic

FIXED = {  # column -> SQL type; metric columns are added after these
    "key": "TEXT PRIMARY KEY",
    "scenario": "TEXT",
    "scenario_path": "TEXT",
    "net_file": "TEXT",
    "controller": "TEXT",
    "seed": "INTEGER",
    "overrides": "TEXT",
    "status": "TEXT NOT NULL CHECK (status IN ('done', 'failed'))",
    "error": "TEXT",
    "started_at": "TEXT",
    "ended_at": "TEXT",
    "wall_s": "REAL",
    "overhead_s": "REAL",
    "artifacts": "TEXT",
    "code": "TEXT",  # code_version() of the plug-in that made the row
}
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: The suffixes :func:`export` writes beside a ledger: a ledger named so would be overwritten by its export.
EXPORT_SUFFIXES = (".csv", ".parquet")


def check(path, flag: str = "--ledger", new_ok: bool = True, needs=()) -> None:
    """``path`` is a ledger, or (``new_ok``: one to write) a file that can be created, not named like its
    exports (.csv, .parquet): not a folder, not a file of another kind, not a SQLite database of
    something else; an existing one has the columns ``needs``. Raises ScenarioError naming ``flag``
    (the ledger and its missing columns)."""
    path = pathlib.Path(path)
    if new_ok:  # one to write; one only read may lie in a read-only folder
        check_out_file(path, flag)
    if new_ok and path.suffix.lower() in EXPORT_SUFFIXES:  # a ledger to write: export() would overwrite it
        raise ScenarioError(CL, flag, "a ledger name not ending in .csv or .parquet (the ledger's CSV and Parquet "
                            "exports are written beside it with those suffixes), e.g. runs.sqlite", str(path))
    if not path.exists():
        if not new_ok:
            raise ScenarioError(CL, flag, "an existing ledger", str(path))
        return
    try:
        with contextlib.closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as con:
            tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            cols = {r[1] for r in con.execute("PRAGMA table_info(runs)")} if "runs" in tables else set()
    except sqlite3.DatabaseError as e:
        raise ScenarioError(CL, flag, f"a ledger (a SQLite file; this one: {e})", str(path)) from None
    if (tables or not new_ok) and not {"key", "status"} <= cols:
        raise ScenarioError(CL, flag, "a ledger (a SQLite file with a table 'runs' of sumo-avoid runs), not another "
                            f"database (tables: {sorted(tables)})", str(path))
    missing = [c for c in needs if c not in cols]
    if cols and missing:
        raise ScenarioError(str(path), "runs", f"a ledger table with the columns {', '.join(needs)} (missing: "
                            f"{', '.join(missing)})", show_got=False)


def connect(path) -> sqlite3.Connection:
    """Open (creating if needed) a ledger; WAL mode, table ``runs``. Raises OutputError if it cannot be
    written (as :func:`record` does)."""
    path = pathlib.Path(path)
    with writing(path):
        path.parent.mkdir(parents=True, exist_ok=True)
        con = sqlite3.connect(path, timeout=30.0, isolation_level=None)  # explicit transactions below
        con.execute("PRAGMA journal_mode=WAL")
        con.execute("PRAGMA synchronous=FULL")
        cols = ", ".join(f'"{c}" {t}' for c, t in FIXED.items())
        con.execute(f"CREATE TABLE IF NOT EXISTS runs ({cols})")
    return con


def columns(con: sqlite3.Connection) -> list[str]:
    return [r[1] for r in con.execute("PRAGMA table_info(runs)")]


def _sql_type(v) -> str:
    if v is None:  # type unknown yet: no affinity, so later numbers stay numbers
        return ""
    if isinstance(v, bool) or isinstance(v, int):
        return "INTEGER"
    if isinstance(v, float):
        return "REAL"
    return "TEXT"


def scalar_metrics(metrics: dict) -> dict:
    """The metrics that become ledger columns: scalars (None included) with plain names."""
    out = {}
    for k, v in metrics.items():
        if k in FIXED or not _NAME.match(k):
            continue
        if v is None or isinstance(v, (bool, int, float, str)):
            out[k] = int(v) if isinstance(v, bool) else v
    return out


CODE_ROOT = pathlib.Path(__file__).resolve().parents[1]  # the sumo_avoid package (this file: studies/)


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """16 hex digits naming the plug-in's code: sha256 of every ``sumo_avoid/**/*.py`` (path and
    bytes) and SUMO's version. A run key covers a run's inputs, not the code; this column tells
    rows made by different code apart."""
    root = CODE_ROOT
    h = hashlib.sha256()
    for f in sorted(root.rglob("*.py")):
        h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes() + b"\0")
    with contextlib.suppress(metadata.PackageNotFoundError):
        h.update(metadata.version("eclipse-sumo").encode())
    return h.hexdigest()[:16]


def made_by_other_code(con: sqlite3.Connection, keys, code: str) -> int:
    """How many of the ``done`` rows among ``keys`` were made by code other than ``code`` (or by a
    version that did not record it)."""
    keys = set(keys)
    col = "code" if "code" in columns(con) else "NULL"  # a ledger from before the column
    return sum(1 for k, c in con.execute(f"SELECT key, {col} FROM runs WHERE status = 'done'")
               if k in keys and c != code)


def status_of(con: sqlite3.Connection) -> dict[str, str]:
    """key -> status of every recorded run."""
    return dict(con.execute("SELECT key, status FROM runs"))


def record(con: sqlite3.Connection, row: dict, metrics: dict | None = None) -> bool:
    """Write one finished run in one transaction. Returns False if a ``done`` row was kept as is. Raises
    OutputError naming the ledger if it cannot be written (a full disk, a read-only folder) or is gone
    from its folder (SQLite would go on writing into the deleted file: the rows would be lost)."""
    path = con.execute("PRAGMA database_list").fetchone()[2]
    with writing(path):
        done = _record(con, row, metrics)
    if not os.path.exists(path):
        raise vanished(path)
    return done


def _record(con: sqlite3.Connection, row: dict, metrics: dict | None) -> bool:
    values = {c: row.get(c) for c in FIXED}
    values.update(scalar_metrics(metrics or {}))
    with _transaction(con):
        have = set(columns(con))
        for c, v in values.items():
            if c not in have:
                con.execute(f'ALTER TABLE runs ADD COLUMN "{c}" {_sql_type(v)}'.rstrip())
        names = list(values)
        cols = ", ".join(f'"{c}"' for c in names)
        marks = ", ".join("?" for _ in names)
        sets = ", ".join(f'"{c}" = excluded."{c}"' for c in names if c != "key")
        # a done row is final: the upsert only replaces a failed one
        cur = con.execute(f"INSERT INTO runs ({cols}) VALUES ({marks}) ON CONFLICT(key) DO UPDATE SET {sets} "
                          f"WHERE runs.status != 'done'", [values[c] for c in names])
        return cur.rowcount > 0


@contextlib.contextmanager
def _transaction(con: sqlite3.Connection):
    con.execute("BEGIN IMMEDIATE")
    try:
        yield
    except BaseException:
        con.execute("ROLLBACK")
        raise
    con.execute("COMMIT")


def read(path):
    """The whole ``runs`` table, ordered by scenario, controller, seed, key."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such ledger")
    with contextlib.closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as con:
        return pd.read_sql("SELECT * FROM runs ORDER BY scenario, controller, seed, key", con)


def row_hashes(path) -> dict[str, str]:
    """key -> sha256 of the row as stored (every column, SQLite values): detects any rewrite."""
    with contextlib.closing(sqlite3.connect(f"file:{pathlib.Path(path)}?mode=ro", uri=True)) as con:
        cur = con.execute("SELECT * FROM runs")
        names = [d[0] for d in cur.description]
        out = {}
        for values in cur:
            rec = {n: v for n, v in zip(names, values) if v is not None}  # columns added later are NULL
            out[rec["key"]] = hashlib.sha256(json.dumps(rec, sort_keys=True).encode()).hexdigest()
    return out


def export(path, out) -> list[pathlib.Path]:
    """Write the table as CSV (always) and Parquet (only if pyarrow is installed) next to ``out``, each
    file whole or not at all.

    ``out`` is a file name; its suffix is replaced by ``.csv`` / ``.parquet``. Returns the files written.
    """
    out = pathlib.Path(out)
    df = read(path)
    written = [out.with_suffix(".csv")]
    write_atomic(written[0], df.to_csv(index=False))
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return written
    written.append(out.with_suffix(".parquet"))
    buf = io.BytesIO()
    df.to_parquet(buf, index=False)
    write_atomic(written[-1], buf.getvalue())
    return written
