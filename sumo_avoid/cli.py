"""``sumo-avoid``: run scenarios and print their metrics.

Bad input (a malformed scenario, override, flag or file) prints one line to stderr naming the
file, the key and what was expected, and exits with code 2, before anything is written; so does an
output that cannot be written (a full disk, a read-only or vanished folder: the path and the OS's reason). Exit
codes (docs/errors.md): 0 ok; 1 runs failed or suite criteria not met; 2 bad input; 3 the run
crashed (SUMO died or raised mid-run); 130 interrupted.
"""
from __future__ import annotations

import argparse
import contextlib
import datetime
import errno
import json
import pathlib
import shutil
import sys
import tempfile

from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import ScenarioError, ScenarioErrors
from sumo_avoid.core.registry import Entry
from sumo_avoid.core.output_error import OutputError, from_errno, reason, writing
from sumo_avoid.runs import faults, runner, worker
from sumo_avoid.runs.job import RunJob, RunOutcome
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.key_reference import format_reference
from sumo_avoid.scenario.plugins import choose
from sumo_avoid.studies import batch, files, report, reproduce, suite, tune, watch_cmd
from sumo_avoid.sumo import console
from sumo_avoid.watch.video import VideoSpec

EXIT_BAD_INPUT = 2
EXIT_CRASHED = 3


class UsageError(Exception):
    """A command line argparse refuses (unknown flag, missing argument, wrong type)."""


class _Parser(argparse.ArgumentParser):
    """argparse, with its refusal as one line (no usage block) and exit code 2 from :func:`main`."""

    def error(self, message):
        command = self.prog.removeprefix("sumo-avoid").strip()  # "run", "batch", ... ("" for the top level)
        raise UsageError(f"{command}: {message}" if command else message)


def _parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="sumo-avoid", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run one scenario, write metrics.json, trajectories.csv and plots")
    r.add_argument("scenario", type=pathlib.Path, help="scenario file (.toml) or SUMO configuration (.sumocfg)")
    r.add_argument("--ego", dest="egos", action="append", default=[], metavar="ID",
                   help="a vehicle of the route files for the plug-in to drive (repeatable; sets ego.ids; "
                        "needed with a .sumocfg)")
    r.add_argument("--seed", type=int, default=None, help="seed for SUMO and the plug-in (default: the scenario's)")
    r.add_argument("--controller", default=None, help="controller name (default: the scenario's)")
    r.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value by its dotted path, e.g. --set sim.duration_s=60")
    r.add_argument("--out", type=pathlib.Path, default=None, help="output folder (default: reports/runs/NAME-...)")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--video", type=pathlib.Path, default=None, metavar="FILE",
                   help="also render the run into FILE.mp4 or FILE.gif (headless; as replay --video)")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    c = sub.add_parser("controllers", help="list the controllers: built in, of installed packages (entry points) "
                                           "and those named (MODULE:ATTR), each with its origin")
    c.add_argument("names", nargs="*", metavar="NAME", help="controllers to look up (a name or MODULE:ATTR)")
    sub.add_parser("keys", help="print every scenario key (Markdown table)")
    for mod in (batch, suite, report, reproduce, tune, watch_cmd):
        mod.add_parser(sub)
    return ap


def _summary(m: dict, out: pathlib.Path) -> str:
    def f(x, fmt="{:.3f}"):
        return "n/a" if x is None else fmt.format(x)

    return "\n".join([
        f"scenario {m['scenario']}  controller {m['controller']}  seed {m['seed']}  sim {m['sim_time_s']:.1f} s",
        f"  goal_reached    {m['goal_reached']}   time_to_goal_s {f(m['time_to_goal_s'], '{:.1f}')}",
        f"  collisions      {m['collisions']}   (SUMO reported {m['sumo_collisions']})",
        f"  min_gap_m       {f(m['min_gap_m'], '{:.2f}')}",
        f"  phi_coll        {f(m['phi_coll'], '{:.3g}')}   phi_wall {f(m['phi_wall'], '{:.3f}')} m",
        f"  mean_speed_mps  {f(m['mean_speed_mps'], '{:.2f}')}   path_length_m {f(m['path_length_m'], '{:.1f}')}",
        f"  -> {out}",
    ])


def cmd_run(args) -> int:
    """Validate, then run the scenario in a child process (the batch's child run, forked from this
    process: runs/worker.py, start "here"): a SUMO crash costs the child, and this one reports it in
    one line (exit code 3)."""
    if args.egos:  # as an override, so that the run's child process loads the same scenario
        args.overrides = [*args.overrides, f"ego.ids={json.dumps(args.egos)}"]
    scn = scenario.load(args.scenario, args.overrides, controller=args.controller, seed=args.seed)
    faults.rules()  # test-only fault injection: a malformed SUMO_AVOID_INJECT_CRASH is refused now
    out = args.out
    if out is None:
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        out = pathlib.Path("reports") / "runs" / f"{scn.name}-{scn.spec.ego.controller}-s{scn.spec.sim.seed}-{stamp}"
    if args.video is not None:
        watch_cmd.check_video_path(args.video, "--video")
    files.refuse_finished_run(out, "--out")  # nothing finished is rewritten
    made = files.make_dirs(out, "--out")  # refused now, not after the run
    kept: list[pathlib.Path] = []
    try:
        with tempfile.TemporaryDirectory(prefix="sumo-avoid-run-") as tmp:
            res = _run_child(args, scn, pathlib.Path(tmp))
            if res.unwritable is not None:  # its own folder filled up, turned read-only or vanished
                raise OutputError(*res.unwritable)
            if res.ok:
                _keep(pathlib.Path(tmp), out, kept)
            elif res.bad_input is None:  # crashed: the log and a failure record, never metrics
                _keep(pathlib.Path(tmp), out, kept, only=("sumo.log",))
                files.write_atomic(out / "failed.json", json.dumps(
                    {"status": "failed", "error": res.error, "where": res.where, "scenario": str(scn.path),
                     "seed": scn.spec.sim.seed,
                     "controller": scn.spec.ego.controller}, indent=2, sort_keys=True) + "\n")
    except BaseException:  # nothing half-written: what this run put into --out goes, and the folders it made
        for f in kept:
            with contextlib.suppress(OSError):  # e.g. on a file system that turned read-only
                f.unlink()
        files.remove_dirs(made)
        raise
    if res.bad_input is not None:  # input SUMO refused only once it ran: nothing written
        files.remove_dirs(made)
        print(f"sumo-avoid: error: {res.bad_input}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not res.ok:
        where = f" at {res.where}" if res.where else ""
        print(f"sumo-avoid: error: {scn.path}: the run crashed: {res.error}{where} (seed {scn.spec.sim.seed}; "
              f"SUMO's log: {out / 'sumo.log'}, failure record: {out / 'failed.json'})", file=sys.stderr)
        return EXIT_CRASHED
    print(_summary(res.metrics, out))
    print(f"  {console.summary_line(out / 'sumo.log')}")
    if args.video is not None:
        return watch_cmd.render(out, args.video, VideoSpec())
    return 0


def cmd_controllers(args) -> int:
    """One line per controller: name, origin (built-in, entry point (DIST), import path), first doc line."""
    rows = [(e.name, e.origin, e.doc) for e in CONTROLLERS.entries()]
    rows += [(name, origin, found.doc if isinstance(found, Entry) else f"(not usable: {found})")
             for name, origin, found in CONTROLLERS.installed()]
    for i, name in enumerate(args.names):
        if name not in {r[0] for r in rows}:
            e = choose(CONTROLLERS, name, "<command line>", f"controllers[{i}]")
            rows.append((e.name, e.origin, e.doc))
    width = max(len(r[0]) for r in rows)
    for name, origin, doc in rows:
        print(f"{name:{width}s}  {origin:24s} {doc}")
    return 0


def _run_child(args, scn, tmp: pathlib.Path) -> RunOutcome:
    """The run in a child process, a progress bar over its simulated time fed from a file."""
    show = not args.quiet and sys.stdout.isatty()
    job = RunJob(str(scn.path.resolve()), args.seed, tuple(args.overrides), args.controller, plots=not args.no_plots,
                 progress=show)
    bar = runner.Progress(scn.spec.sim.duration_s) if show else None

    def poll() -> None:
        if bar is not None:
            bar.bar.update(max(0.0, min(_sim_time(tmp / "progress"), bar.bar.total) - bar.bar.n))

    try:
        res = worker.run_in(tmp, job, start="here", poll=poll)
    finally:
        if bar is not None:
            bar.on_end()
    if res.ok:  # what the run printed besides SUMO's messages, e.g. Python warnings
        for line in console.leftover(tmp / "stderr.txt", tmp / "sumo.log"):
            print(line, file=sys.stderr)
    return res


def _sim_time(path: pathlib.Path) -> float:
    try:
        return float(path.read_bytes() or 0.0)
    except (OSError, ValueError):
        return 0.0


_RUN_FILES = ("result.json", "stdout.txt", "stderr.txt", "progress")


def _keep(tmp: pathlib.Path, out: pathlib.Path, kept: list, only=None) -> None:
    """Move the run's outputs from its private folder into ``out`` (an existing folder), each path in
    ``kept`` before it is written; raises OutputError naming the file that cannot be written. A folder of a
    file's name in ``out`` is refused before anything moves (a move would put the file inside it)."""
    names = [f.name for f in sorted(tmp.iterdir()) if f.name not in _RUN_FILES and (only is None or f.name in only)]
    for name in names:
        if (out / name).is_dir():
            raise from_errno(errno.EISDIR, out / name)
    for f in sorted(tmp.iterdir()):
        if f.name in names:
            kept.append(out / f.name)
            with writing(out / f.name):  # a vanished ``out`` is not made again
                shutil.move(str(f), str(out / f.name))


def main(argv=None) -> int:
    try:
        args = _parser().parse_args(argv)
    except UsageError as e:
        print(f"sumo-avoid: error: <command line>: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if args.command == "run":
            return cmd_run(args)
        if getattr(args, "func", None) is not None:  # batch, suite, report, reproduce, tune, replay
            return args.func(args)
        if args.command == "controllers":
            return cmd_controllers(args)
        if args.command == "keys":
            print(format_reference())
            return 0
    except KeyboardInterrupt:
        print("sumo-avoid: interrupted", file=sys.stderr)
        return 130
    except OutputError as e:  # a full disk, a read-only or vanished folder: the path and the OS's reason
        print(f"sumo-avoid: error: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as e:  # any other file the system refused (each write above names its own path)
        print(f"sumo-avoid: error: {e.filename or '<file>'}: {reason(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ScenarioErrors as e:  # every bad input of a batch, one line each
        for err in e.errors:
            print(f"sumo-avoid: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except ScenarioError as e:
        cause = f" (SUMO: {e.__cause__})" if e.__cause__ is not None else ""
        print(f"sumo-avoid: error: {e}{cause}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 1


if __name__ == "__main__":
    sys.exit(main())
