"""The run viewers a study report links (``report LEDGER --out R.html``: one page per done run in
``R_viewers/KEY.html`` beside the report) and a suite's JUnit XML names (``JUNIT_viewers/ENTRY-sSEED.html``
beside it, for the runs of a failed entry).

A report plans its viewers (:func:`plan`), writes its page with their links, then the viewers
(:func:`write_planned`); if one cannot be written, the page and the viewers written so far are
removed again (nothing half-written) and the error names the file."""
from __future__ import annotations

import contextlib
import html
import os
import pathlib

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.studies.files import write_atomic
from sumo_avoid.studies.watch_cmd import write_viewer


def viewers_dir(out: pathlib.Path) -> pathlib.Path:
    return out.with_name(f"{out.stem}_viewers")


def _artifacts(row, base: pathlib.Path) -> pathlib.Path | None:
    a = row.get("artifacts")
    if not isinstance(a, str) or not a:
        return None
    p = pathlib.Path(a)
    p = p if p.is_absolute() else base / p
    return p if (p / "trajectories.csv").is_file() else None


def _net(row) -> str | None:
    return row.get("net_file") if isinstance(row.get("net_file"), str) else None


def plan(df, base: pathlib.Path, report: pathlib.Path) -> dict:
    """key -> (run folder, net file or None, viewer file) of each done run with a recording."""
    folder = viewers_dir(report)
    out = {}
    for row in df[df["status"] == "done"].to_dict(orient="records"):
        d = _artifacts(row, base)
        if d is not None:
            out[row["key"]] = (d, _net(row), folder / f"{str(row['key'])[:16]}.html")
    return out


def links(planned: dict, report: pathlib.Path) -> dict:
    """key -> link of its viewer, relative to the report."""
    return {k: os.path.relpath(path, report.parent) for k, (_, _, path) in planned.items()}


def write_planned(planned: dict) -> None:
    """Write every planned viewer (a run whose files no longer read gets a page saying why); on failure
    remove what was written and raise."""
    written: list[pathlib.Path] = []
    folders = sorted({path.parent for _, _, path in planned.values()})
    made = [f for f in folders if not f.exists()]
    try:
        for f in made:
            f.mkdir()
        for d, net, path in planned.values():
            try:
                write_viewer(d, path, net_file=net)
            except ScenarioError as e:
                write_atomic(path, f"<!DOCTYPE html><meta charset='utf-8'><p>No viewer: {html.escape(str(e))}</p>\n")
            written.append(path)
    except BaseException:
        for path in written:
            with contextlib.suppress(OSError):
                path.unlink()
        for f in made:
            with contextlib.suppress(OSError):
                f.rmdir()
        raise


def link(href: str | None) -> str:
    return f'<a href="{html.escape(href)}">view</a>' if href else "n/a"
