"""``sumo-avoid replay RUN_DIR``: watch a finished run, in sumo-gui (:mod:`sumo_avoid.watch.gui_replay`)
or as a video rendered headless (``--video FILE.mp4|FILE.gif``, :mod:`sumo_avoid.watch.video`); and the
run viewer files the reports link (``report RUN_DIR``, ``report LEDGER``, a suite's JUnit XML).

Bad input (no run folder, ``--from`` after ``--to``, a video name that is no .mp4 or .gif, an output
that cannot be written, sumo-gui without a display) is one line, exit code 2, nothing written."""
from __future__ import annotations

import math
import os
import pathlib
import sys
import tempfile

import traci  # the exceptions of sumo-gui's remote control
from sumo_avoid.core.config import ScenarioError
from sumo_avoid.studies.files import CL, check_out_file, make_dirs, remove_dirs, write_atomic
from sumo_avoid.watch import recording
from sumo_avoid.watch.gui_replay import ReplaySpec, replay
from sumo_avoid.watch.video import HEIGHT_PX, WIDTH_PX, VideoSpec, write_video
from sumo_avoid.watch.viewer import viewer_html

VIDEO_SUFFIXES = (".mp4", ".gif")


def add_parser(sub) -> None:
    r = sub.add_parser("replay", help="replay a run in sumo-gui, or render it into a video (--video)")
    r.add_argument("run_dir", type=pathlib.Path, metavar="RUN_DIR")
    r.add_argument("--from", dest="t_from", type=float, default=None, metavar="S", help="start at this time, s")
    r.add_argument("--to", dest="t_to", type=float, default=None, metavar="S", help="end at this time, s")
    r.add_argument("--speed", type=float, default=1.0, metavar="X", help="recorded seconds per second (default 1)")
    r.add_argument("--video", type=pathlib.Path, default=None, metavar="FILE",
                   help="render headless into FILE.mp4 or FILE.gif instead of opening sumo-gui")
    r.add_argument("--fps", type=float, default=10.0, help="video frames per second (default 10)")
    r.add_argument("--screenshot", type=pathlib.Path, default=None, metavar="FILE.png",
                   help="save sumo-gui's view at --at (and its bounds in FILE.png.json)")
    r.add_argument("--at", type=float, default=None, metavar="S", help="time of the screenshot, s")
    r.set_defaults(func=cmd_replay)


def check_video_path(path: pathlib.Path, flag: str) -> None:
    if path.suffix.lower() not in VIDEO_SUFFIXES:
        raise ScenarioError(CL, flag, "a video file name ending in .mp4 or .gif", str(path))
    check_out_file(path, flag)


def _check(args) -> None:
    for flag, v in (("--from", args.t_from), ("--to", args.t_to), ("--at", args.at)):
        if v is not None and not math.isfinite(v):
            raise ScenarioError(CL, flag, "a time in seconds", v)
    if args.t_from is not None and args.t_to is not None and args.t_from >= args.t_to:
        raise ScenarioError(CL, "--to", f"a time after --from ({args.t_from})", args.t_to)
    for flag, v in (("--speed", args.speed), ("--fps", args.fps)):
        if not 0 < v < math.inf:
            raise ScenarioError(CL, flag, "a positive number", v)
    if args.video is not None:
        check_video_path(args.video, "--video")
        if args.screenshot is not None:
            raise ScenarioError(CL, "--screenshot", "no --screenshot with --video (the screenshot is sumo-gui's)",
                                str(args.screenshot))
    if args.screenshot is not None:
        check_out_file(args.screenshot, "--screenshot")


def cmd_replay(args) -> int:
    _check(args)
    if args.video is not None:
        return render(args.run_dir, args.video, VideoSpec(args.fps, args.t_from, args.t_to, args.speed))
    rec = recording.load(args.run_dir)
    if rec.net_file is None:
        raise ScenarioError(str(args.run_dir), "RUN_DIR", "a run whose net is known (replay.json names an existing "
                            "net file; runs of this version write it)", show_got=False)
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        raise ScenarioError(CL, "replay", "a display for sumo-gui (DISPLAY is not set): --video FILE.mp4 renders "
                            "without one, or run under xvfb-run", show_got=False)
    made = make_dirs(args.screenshot.parent, "--screenshot") if args.screenshot else []
    try:
        with tempfile.TemporaryDirectory(prefix="sumo-avoid-replay-") as tmp:
            out = replay(rec, ReplaySpec(args.t_from, args.t_to, args.speed, args.screenshot, args.at),
                         pathlib.Path(tmp))
    except (traci.exceptions.FatalTraCIError, traci.exceptions.TraCIException) as e:
        remove_dirs(made)
        print(f"sumo-avoid: error: {args.run_dir}: sumo-gui ended the replay early (its window closed, or it "
              f"stopped: its messages above): {e}", file=sys.stderr)
        return 1
    except BaseException:
        remove_dirs(made)
        raise
    print(f"replayed {out['steps']} steps of {args.run_dir}" +
          (f"; screenshot -> {out['screenshot']}" if out["screenshot"] else ""), file=sys.stdout)
    return 0


def render(run_dir, video: pathlib.Path, spec: VideoSpec) -> int:
    """``--video``: the run rendered into ``video`` (checked by :func:`check_video_path` before)."""
    rec = recording.load(run_dir)
    made = make_dirs(video.parent, "--video")
    try:
        n = write_video(rec, video, spec)
    except BaseException:
        remove_dirs(made)
        raise
    print(f"video -> {video} ({n} frames, {WIDTH_PX}x{HEIGHT_PX}, {spec.fps:g} fps)")
    return 0


def write_viewer(run_dir, out: pathlib.Path, net_file=None) -> pathlib.Path:
    """The run's viewer page written to ``out`` (whole or not at all)."""
    write_atomic(out, viewer_html(recording.load(run_dir, net_file=net_file)))
    return out
