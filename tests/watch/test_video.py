"""``sumo-avoid replay --video`` headless on a short real run: the frame count (duration x fps), the
size, and where frame k shows the ego (its blue pixels mapped back to net metres through the frame's
view) against the recording."""
from __future__ import annotations

import imageio.v2 as imageio
import numpy as np
import pytest
from watch_runs import crash_run  # noqa: F401  (a fixture)

from sumo_avoid.cli import main
from sumo_avoid.watch import recording
from sumo_avoid.watch.recording import at_time
from sumo_avoid.watch.video import EGO_RGB, HEIGHT_PX, WIDTH_PX, VideoSpec, frame_times, view_at

pytestmark = pytest.mark.sumo


def ego_xy(frame: np.ndarray, view) -> np.ndarray:
    """Centre of the ego's pixels (its fill colour) in net metres."""
    rgb = np.array([int(EGO_RGB[i:i + 2], 16) for i in (1, 3, 5)])
    v, u = np.nonzero(np.abs(frame[:, :, :3].astype(int) - rgb).sum(axis=2) < 40)
    assert len(u) > 50, "no ego in the frame"
    x0, y0, x1, y1 = view
    return np.array([x0 + (u.mean() + 0.5) / WIDTH_PX * (x1 - x0), y1 - (v.mean() + 0.5) / HEIGHT_PX * (y1 - y0)])


@pytest.mark.parametrize("suffix", [".mp4", ".gif"])
def test_frames_size_and_the_ego_where_the_recording_has_it(crash_run, tmp_path, suffix):
    video = tmp_path / f"run{suffix}"
    t_from, t_to, fps = 2.0, 6.0, 10.0
    assert main(["replay", str(crash_run), "--video", str(video), "--from", str(t_from), "--to", str(t_to),
                 "--fps", str(fps)]) == 0
    frames = [f for f in imageio.get_reader(video)]  # (list() asks the reader its length: inf for a stream)
    assert abs(len(frames) - (t_to - t_from) * fps) <= 1
    assert frames[0].shape[:2] == (HEIGHT_PX, WIDTH_PX)
    rec = recording.load(crash_run)
    times = frame_times(rec, VideoSpec(fps, t_from, t_to))
    for k in (0, 17, len(frames) - 1):
        ego = at_time(rec.traj[rec.traj["id"] == "ego"], times[k]).iloc[0]
        seen = ego_xy(frames[k], view_at(rec, times[k]))
        assert np.hypot(*(seen - [ego["x"], ego["y"]])) < 0.3, (k, seen, ego[["x", "y"]].tolist())
