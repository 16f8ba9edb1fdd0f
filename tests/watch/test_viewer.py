"""The run viewer of a real run in headless Chromium (Debian's package, driven from the command line:
``--dump-dom`` returns the page after its script ran, which writes its state into ``<pre id="state">``;
``--enable-logging=stderr`` prints every console message and uncaught error as a ``CONSOLE`` line)."""
from __future__ import annotations

import json
import re
import subprocess

import pytest
from watch_runs import crash_run, tool  # noqa: F401  (crash_run: a fixture)

from sumo_avoid.cli import main
from sumo_avoid.watch import recording
from sumo_avoid.watch.viewer import page_data, stride, viewer_html

pytestmark = pytest.mark.sumo


def chromium(*args: str) -> subprocess.CompletedProcess:
    exe = tool("chromium", "chromium-browser", why="the viewer test opens the page in headless Chromium")
    return subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                           "--enable-logging=stderr", "--v=0", "--virtual-time-budget=3000", *args],
                          capture_output=True, text=True, timeout=90, check=False)


def page_state(url: str) -> tuple[dict, list[str]]:
    """(the page's state after its script ran, the console lines Chromium logged)."""
    p = chromium("--dump-dom", url)
    m = re.search(r'<pre id="state"[^>]*>(.*?)</pre>', p.stdout, re.S)
    assert m, f"no state in the page (chromium exit {p.returncode}): {p.stderr[-2000:]}"
    console = [ln for ln in p.stderr.splitlines() if "CONSOLE" in ln]
    return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&")), console


def test_slider_at_the_collision_shows_the_two_footprints_touching(crash_run, tmp_path):
    assert main(["report", str(crash_run)]) == 0  # the viewer of one run folder
    page = crash_run / "viewer.html"
    event = recording.load(crash_run).metrics["collision_events"][0]
    state, console = page_state(f"{page.as_uri()}#t={event['time_s']}")
    assert console == [] and state["errors"] == []
    assert abs(state["time_s"] - event["time_s"]) < 1e-9
    assert [event["a"], event["b"]] in state["touching"]
    before, _ = page_state(f"{page.as_uri()}#t=1.0")
    assert before["time_s"] == 1.0 and before["touching"] == []
    shot = tmp_path / "viewer.png"
    chromium("--window-size=1400,760", f"--screenshot={shot}", f"{page.as_uri()}#t={event['time_s']}")
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"  # docs/images/viewer_collision.png, looked at once


def test_thinning_keeps_every_event_step_and_the_file_small(crash_run):
    rec = recording.load(crash_run)
    full = page_data(rec)
    assert full["stride"] == 1 and len(full["times"]) == rec.traj["step"].nunique()
    thin = page_data(rec, max_rows=60)  # 300 rows: every 5th step
    assert thin["stride"] == stride(len(rec.traj), rec.traj["step"].nunique(), 60) == 5
    assert all(any(abs(t - e["t"]) < 1e-9 for t in thin["times"]) for e in thin["events"])
    page = viewer_html(rec)
    assert len(page) < 20e6 and not re.search(r"(src|href)\s*=", page)  # nothing to fetch: works offline


def test_a_big_traffic_run_is_thinned_below_20_mb(crash_run):
    """500 vehicles for 120 s at 0.1 s (600 000 footprints): every k-th step kept, the page < 20 MB."""
    import dataclasses

    import numpy as np
    import pandas as pd

    rec = recording.load(crash_run)
    steps, n = 1200, 500
    s, v = np.repeat(np.arange(1, steps + 1), n), np.tile(np.arange(n), steps)
    big = pd.DataFrame({"step": s, "time_s": s * 0.1, "id": [f"v{i}" for i in v], "is_ego": v == 0,
                        "x": 1000 * np.random.default_rng(1).random(len(s)) + 0.123456, "y": -8.75 + 0.0 * s,
                        "vx": 13.891, "vy": 0.0, "speed": 13.891, "heading": 0.012345, "length": 4.5, "width": 1.8})
    rec = dataclasses.replace(rec, traj=big, ssm=None)
    page = viewer_html(rec)
    data = json.loads(page.split("window.RUN=")[1].split(";</script>")[0])
    assert data["stride"] >= 2 and len(page) < 20e6


@pytest.mark.parametrize("table, text", [("signals.csv", "garbage\n1\n"), ("persons.csv", "a,b\n1,2\n"),
                                         ("ssm_conflicts.csv", "ego\nx\n")])
def test_a_run_folder_with_a_table_not_written_by_a_run_is_one_line_exit_2(crash_run, tmp_path, capsys, table, text):
    import shutil

    run = tmp_path / "run"
    shutil.copytree(crash_run, run)
    (run / table).write_text(text)
    out = tmp_path / "report.html"
    assert main(["report", str(run), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and table in err[0] and "no column" in err[0]
    assert not out.exists()
