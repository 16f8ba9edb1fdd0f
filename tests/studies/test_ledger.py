"""The SQLite ledger: one row per key, done rows final, metrics as columns, CSV export."""
import pathlib
import sqlite3

import pandas as pd
import pytest

from sumo_avoid.studies import ledger


def _row(key, status="done", error=None, seed=1):
    return {"key": key, "scenario": "s", "controller": "c", "seed": seed, "status": status, "error": error,
            "started_at": "t0", "ended_at": "t1", "wall_s": 1.0}


def test_record_adds_metric_columns_and_reads_with_pandas(tmp_path):
    db = tmp_path / "l.sqlite"
    con = ledger.connect(db)
    assert ledger.record(con, _row("a"), {"collisions": 0, "min_gap_m": 1.5, "goal_reached": True,
                                         "collision_events": [], "per_ego": {"e": {}}, "time_to_goal_s": None})
    assert ledger.record(con, _row("b", "failed", "worker died: SIGSEGV (segmentation fault)"))
    con.close()
    assert sqlite3.connect(db).execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    df = pd.read_sql("SELECT * FROM runs ORDER BY key", sqlite3.connect(db))
    assert list(df["key"]) == ["a", "b"]
    assert {"collisions", "min_gap_m", "goal_reached", "time_to_goal_s"} <= set(df.columns)
    assert "collision_events" not in df.columns and "per_ego" not in df.columns  # nested: in metrics.json
    assert df.loc[0, "min_gap_m"] == 1.5 and df.loc[0, "goal_reached"] == 1
    assert df.loc[1, "error"].startswith("worker died: SIGSEGV")
    con = ledger.connect(db)  # a metric first seen without a value keeps later numbers numeric
    ledger.record(con, _row("c"), {"time_to_goal_s": 79.5, "collisions": 0})
    assert con.execute("SELECT typeof(time_to_goal_s) FROM runs WHERE key = 'c'").fetchone()[0] == "real"


def test_done_row_is_never_rewritten_failed_row_is_replaced(tmp_path):
    db = tmp_path / "l.sqlite"
    con = ledger.connect(db)
    ledger.record(con, _row("a"), {"collisions": 0})
    ledger.record(con, _row("b", "failed", "boom"))
    before = ledger.row_hashes(db)
    assert not ledger.record(con, _row("a", seed=99), {"collisions": 7})  # ignored
    assert ledger.record(con, _row("b"), {"collisions": 1})  # a retry of a failed run
    after = ledger.row_hashes(db)
    assert after["a"] == before["a"] and after["b"] != before["b"]
    df = ledger.read(db)
    assert len(df) == 2 and set(df["status"]) == {"done"}
    assert ledger.status_of(con) == {"a": "done", "b": "done"}


def test_status_is_checked_and_export_writes_csv(tmp_path):
    db = tmp_path / "l.sqlite"
    con = ledger.connect(db)
    with pytest.raises(sqlite3.IntegrityError):
        ledger.record(con, _row("x", "maybe"))
    assert ledger.status_of(con) == {}  # the failed transaction left nothing behind
    ledger.record(con, _row("a"), {"collisions": 0})
    files = ledger.export(db, tmp_path / "out.any")
    assert files[0].suffix == ".csv"
    assert pd.read_csv(files[0])["key"].tolist() == ["a"]
    for f in files[1:]:  # parquet only when pyarrow is installed
        assert f.suffix == ".parquet" and f.is_file()


def test_code_version_and_rows_made_by_other_code(tmp_path):
    v = ledger.code_version()
    assert len(v) == 16 and int(v, 16) >= 0 and v == ledger.code_version()
    con = ledger.connect(tmp_path / "l.sqlite")
    ledger.record(con, {**_row("a"), "code": v})
    ledger.record(con, {**_row("b"), "code": "0123456789abcdef"})
    ledger.record(con, _row("c"))  # no code recorded (made before the column existed)
    ledger.record(con, {**_row("d", "failed", "boom"), "code": "0123456789abcdef"})  # failed: re-run anyway
    assert ledger.made_by_other_code(con, ["a", "b", "c", "d"], v) == 2
    assert ledger.made_by_other_code(con, ["a"], v) == 0 and ledger.made_by_other_code(con, [], v) == 0


def test_code_version_hashes_the_whole_package():
    """The code column must change with any module of the package, not only with studies/."""
    import sumo_avoid
    from sumo_avoid.studies.ledger import CODE_ROOT

    assert CODE_ROOT == pathlib.Path(sumo_avoid.__file__).resolve().parent
    assert (CODE_ROOT / "rollout" / "loop.py").is_file()
