"""The run viewers a study report links (``report LEDGER --out R.html``: one page per done run in
``R_viewers/KEY.html`` beside the report) and a suite's JUnit XML names (``JUNIT_viewers/ENTRY-sSEED.html``
beside it, for the runs of a failed entry)."""
from __future__ import annotations

import contextlib
import html
import os
import pathlib

from sumo_avoid.core.config import ScenarioError
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


def viewer_for(row, base: pathlib.Path, out: pathlib.Path) -> pathlib.Path | None:
    """Write the viewer of one ledger row's run to ``out``; None where its recording is gone or unreadable."""
    d = _artifacts(row, base)
    if d is None:
        return None
    net = row.get("net_file") if isinstance(row.get("net_file"), str) else None
    try:
        return write_viewer(d, out, net_file=net)
    except ScenarioError:  # a run folder that lost its files: no viewer, the report says so
        return None


def write_viewers(df, base: pathlib.Path, report: pathlib.Path) -> dict:
    """key -> link (relative to the report) of each done run's viewer."""
    folder = viewers_dir(report)
    links = {}
    for row in df[df["status"] == "done"].to_dict(orient="records"):
        if _artifacts(row, base) is None:
            continue
        folder.mkdir(exist_ok=True)
        path = viewer_for(row, base, folder / f"{str(row['key'])[:16]}.html")
        if path is not None:
            links[row["key"]] = os.path.relpath(path, report.parent)
    with contextlib.suppress(OSError):
        folder.rmdir()  # only if nothing was written
    return links


def link(href: str | None) -> str:
    return f'<a href="{html.escape(href)}">view</a>' if href else "n/a"
