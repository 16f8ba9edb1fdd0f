"""A run as a video, rendered headless with the project's own matplotlib drawing (Agg canvas: no
display, no GUI): the road from the net (:func:`sumo_avoid.plots.trajectories.draw_road`), every
vehicle's footprint and every person at each frame's time, the egos in blue, a time stamp and the
ego's speed. MP4 through imageio's ffmpeg (the ``imageio-ffmpeg`` wheel bundles the binary), GIF
through Pillow.

Frame k shows the recorded step at or just before ``t_from + k / fps``; there are
``round((t_to - t_from) * fps)`` frames. The view (:func:`view_at`) is fixed on the egos' whole path
where that fits in ``FIT_M`` (a 4:3 box), else it follows the first ego ``FOLLOW_M`` across; pixel
(u, v) of a frame is world point ``(x0 + (u + 0.5) / W * (x1 - x0), y1 - (v + 0.5) / H * (y1 - y0))``.
"""
from __future__ import annotations

import dataclasses
import os
import pathlib

import imageio.v2 as imageio  # the MP4 encoder (through imageio-ffmpeg's bundled ffmpeg)
import numpy as np
from matplotlib.patches import Circle
from matplotlib.patches import Polygon as MplPolygon
from PIL import Image  # the GIF encoder

from sumo_avoid.core.output_error import writing
from sumo_avoid.plots.trajectories import EGO_COLOURS, _new_figure, draw_road, footprint_corners
from sumo_avoid.road.network import Road
from sumo_avoid.watch.recording import Recording, at_time

WIDTH_PX, HEIGHT_PX = 800, 600
FIT_M = (160.0, 120.0)  # the egos' path within this (plus a margin): one fixed view
FOLLOW_M = 80.0  # else a view this wide follows the first ego
EGO_RGB = EGO_COLOURS[0]
OTHER_RGB = "#2f8f2f"
PERSON_RGB = "#7a2bd1"


@dataclasses.dataclass(frozen=True)
class VideoSpec:
    fps: float = 10.0
    t_from_s: float | None = None  # default: the recording's first step
    t_to_s: float | None = None  # default: its last step
    speed: float = 1.0  # recorded seconds per video second


def frame_times(rec: Recording, spec: VideoSpec) -> np.ndarray:
    """The recorded time each frame shows (before snapping to the step at or before it)."""
    ts = rec.times_s
    t0 = ts[0] if spec.t_from_s is None else max(ts[0], spec.t_from_s)
    t1 = ts[-1] if spec.t_to_s is None else min(ts[-1], spec.t_to_s)
    n = max(1, int(round((t1 - t0) * spec.fps / spec.speed)))
    return t0 + np.arange(n) * spec.speed / spec.fps


def _ego_path(rec: Recording):
    e = rec.traj[rec.traj["is_ego"]]
    return e if len(e) else rec.traj


def view_at(rec: Recording, t_s: float) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) of the view at ``t_s``, 4:3 (see the module docstring)."""
    p = _ego_path(rec)
    xmin, xmax, ymin, ymax = p["x"].min() - 15, p["x"].max() + 15, p["y"].min() - 15, p["y"].max() + 15
    if xmax - xmin <= FIT_M[0] and ymax - ymin <= FIT_M[1]:
        cx, cy, w = (xmin + xmax) / 2, (ymin + ymax) / 2, max(xmax - xmin, (ymax - ymin) * 4 / 3)
    else:
        row = at_time(p[p["id"] == p["id"].iloc[0]], t_s).iloc[0]
        cx, cy, w = float(row["x"]), float(row["y"]), FOLLOW_M
    h = w * HEIGHT_PX / WIDTH_PX
    return cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2


def frames(rec: Recording, spec: VideoSpec):
    """Yield each frame as an (H, W, 3) uint8 array."""
    fig = _new_figure((WIDTH_PX / 100, HEIGHT_PX / 100))
    fig.set_dpi(100)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_axis_off()
    fig.patch.set_facecolor("#eef1ea")
    if rec.net_file is not None:
        draw_road(ax, Road.from_net_file(str(rec.net_file)))
    ax.set_aspect("auto")
    stamp = ax.text(0.01, 0.98, "", transform=ax.transAxes, va="top", ha="left", fontsize=12, family="monospace",
                    bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="#333333", alpha=0.9), zorder=20)
    ax.text(0.99, 0.02, rec.title, transform=ax.transAxes, va="bottom", ha="right", fontsize=9, color="#333333",
            zorder=20)
    moving: list = []
    for t in frame_times(rec, spec):
        for a in moving:
            a.remove()
        moving = []
        rows = at_time(rec.traj, t)
        c = footprint_corners(rows["x"], rows["y"], rows["heading"], rows["length"], rows["width"])
        for poly, ego in sorted(zip(c, rows["is_ego"]), key=lambda pe: pe[1]):
            moving.append(ax.add_patch(MplPolygon(poly, closed=True, facecolor=EGO_RGB if ego else OTHER_RGB,
                                                  edgecolor="black", lw=0.6, zorder=10 + ego)))
        if rec.persons is not None and len(rec.persons):
            for x, y, ln in at_time(rec.persons, t)[["x", "y", "length"]].itertuples(index=False):
                moving.append(ax.add_patch(Circle((x, y), max(0.3, ln / 2), color=PERSON_RGB, zorder=9)))
        egos = rows[rows["is_ego"]]
        speeds = "  ".join(f"{i} {v:5.2f} m/s" for i, v in zip(egos["id"], egos["speed"]))
        stamp.set_text(f"t = {t:6.1f} s  {speeds}")
        x0, y0, x1, y1 = view_at(rec, t)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        fig.canvas.draw()
        yield np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()


def write_video(rec: Recording, path, spec: VideoSpec) -> int:
    """Render and encode to ``path`` (.mp4 or .gif) whole or not at all (a temporary file beside it,
    renamed); returns the number of frames. Raises OutputError naming ``path``."""
    path = pathlib.Path(path)
    tmp = path.with_name(f".{path.stem}.part{path.suffix}")
    n = 0
    with writing(tmp, discard=True):
        if path.suffix.lower() == ".gif":
            images = [Image.fromarray(f).quantize(colors=64) for f in frames(rec, spec)]
            images[0].save(tmp, save_all=True, append_images=images[1:], duration=int(round(1000 / spec.fps)), loop=0)
            n = len(images)
        else:
            with imageio.get_writer(tmp, fps=spec.fps, codec="libx264", quality=8, macro_block_size=8,
                                    ffmpeg_log_level="error", format="FFMPEG") as w:
                for f in frames(rec, spec):
                    w.append_data(f)
                    n += 1
    with writing(path, discard=False):
        os.replace(tmp, path)
    return n
