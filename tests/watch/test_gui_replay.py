"""``sumo-avoid replay`` on the overtaking scenario in sumo-gui under a virtual display (Xvfb): the
screenshot at 20 s shows the ego (magenta) where the recording has it, its pixels mapped to net
metres through the view's bounds sumo-gui reported (FILE.png.json)."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import imageio.v2 as imageio
import numpy as np
import pytest
from watch_runs import crash_run, run_dir, tool  # noqa: F401  (crash_run: a fixture)

from sumo_avoid.watch import recording
from sumo_avoid.watch.recording import at_time

pytestmark = pytest.mark.sumo


@pytest.fixture()
def display():
    """A fresh virtual display (Xvfb picks a free number and writes it to the pipe)."""
    exe = tool("Xvfb", why="sumo-gui needs a display; the test gives it a virtual one")
    r, w = os.pipe()
    proc = subprocess.Popen([exe, "-displayfd", str(w), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                            pass_fds=(w,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(w)
    with os.fdopen(r) as f:
        number = f.readline().strip()
    try:
        assert number, "Xvfb did not start"
        yield f":{number}"
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_sumo_gui_screenshot_shows_the_ego_where_the_recording_has_it(tmp_path_factory, display, tmp_path):
    run = run_dir(tmp_path_factory, "overtaking", "--set", "sim.duration_s=25")
    shot = tmp_path / "gui.png"
    p = subprocess.run([sys.executable, "-m", "sumo_avoid.cli", "replay", str(run), "--from", "18", "--to", "21",
                        "--speed", "1000", "--screenshot", str(shot), "--at", "20"],
                       env={**os.environ, "DISPLAY": display}, capture_output=True, text=True, timeout=120, check=False)
    if p.returncode != 0 and "cannot open display" in p.stderr.lower():
        pytest.skip(f"sumo-gui cannot start on the virtual display: {p.stderr.strip()[-300:]}")
    assert p.returncode == 0, p.stderr
    img = imageio.imread(shot)[:, :, :3].astype(int)
    v, u = np.nonzero((img[:, :, 0] > 200) & (img[:, :, 1] < 80) & (img[:, :, 2] > 200))  # the ego's magenta
    assert len(u) > 100, "no ego in the screenshot"
    meta = json.loads(shot.with_name(shot.name + ".json").read_text())
    x0, y0, x1, y1 = meta["bounds_m"]
    h, w = img.shape[:2]
    seen = np.array([x0 + (u.mean() + 0.5) / w * (x1 - x0), y1 - (v.mean() + 0.5) / h * (y1 - y0)])
    rec = recording.load(run)
    ego = at_time(rec.traj[rec.traj["id"] == "ego"], meta["time_s"]).iloc[0]
    assert meta["time_s"] == 20.0
    assert np.hypot(*(seen - [ego["x"], ego["y"]])) < 1.0, (seen, ego[["x", "y"]].tolist())


def test_without_a_display_it_is_one_line_pointing_to_video(crash_run, monkeypatch, capsys):
    from sumo_avoid.cli import main

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["replay", str(crash_run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--video" in err and "DISPLAY" in err
