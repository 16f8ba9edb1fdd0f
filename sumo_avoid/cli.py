"""``sumo-avoid``: run scenarios and print their metrics.

Bad input (a malformed scenario or override) prints one line to stderr naming the file, the key
and what was expected, and exits with code 2, before anything is written.
"""
from __future__ import annotations

import argparse
import datetime
import pathlib
import shutil
import sys
import tempfile

from sumo_avoid import outputs as evaluate
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import ScenarioError
from sumo_avoid.rollout import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.reference import format_reference
from sumo_avoid.studies import batch, report, reproduce, suite, tune
from sumo_avoid.sumo import console

EXIT_BAD_INPUT = 2


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="sumo-avoid", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="run one scenario, write metrics.json, trajectories.csv and plots")
    r.add_argument("scenario", type=pathlib.Path)
    r.add_argument("--seed", type=int, default=None, help="seed for SUMO and the plug-in (default: the scenario's)")
    r.add_argument("--controller", default=None, help="controller name (default: the scenario's)")
    r.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value by its dotted path, e.g. --set sim.duration_s=60")
    r.add_argument("--out", type=pathlib.Path, default=None, help="output folder (default: reports/runs/NAME-...)")
    r.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    sub.add_parser("controllers", help="list the controllers")
    sub.add_parser("keys", help="print every scenario key (Markdown table)")
    for mod in (batch, suite, report, reproduce, tune):
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
    scn = scenario.load(args.scenario, args.overrides, controller=args.controller, seed=args.seed)
    out = args.out
    if out is None:
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        out = pathlib.Path("reports") / "runs" / f"{scn.name}-{scn.spec.ego.controller}-s{scn.spec.sim.seed}-{stamp}"
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-run-") as tmp:  # nothing in OUT until the run is good
        log, native = pathlib.Path(tmp) / "sumo.log", pathlib.Path(tmp) / "stderr.txt"
        try:
            with console.sumo_console_to(native):  # SUMO's warnings: sumo.log only, counted below
                res = runner.run(scn, log_file=log, progress=not args.quiet and sys.stdout.isatty())
        finally:
            for line in console.leftover(native, log):
                print(line, file=sys.stderr)
        out.mkdir(parents=True, exist_ok=True)
        shutil.move(log, out / "sumo.log")
    m = evaluate.write_outputs(res, out, plots=scn.spec.output.plots and not args.no_plots)
    print(_summary(m, out))
    print(f"  {console.summary_line(out / 'sumo.log')}")
    return 0


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "run":
            return cmd_run(args)
        if getattr(args, "func", None) is not None:  # batch, suite, report, reproduce, tune
            return args.func(args)
        if args.command == "controllers":
            for entry in CONTROLLERS.entries():
                print(f"{entry.name:10s} {entry.doc}")
            return 0
        if args.command == "keys":
            print(format_reference())
            return 0
    except ScenarioError as e:
        cause = f" (SUMO: {e.__cause__})" if e.__cause__ is not None else ""
        print(f"sumo-avoid: error: {e}{cause}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 1


if __name__ == "__main__":
    sys.exit(main())
