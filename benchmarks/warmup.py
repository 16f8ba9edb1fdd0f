"""What a district's warm-up costs the plug-in: the steps before its first ego departs, when SUMO fills the
district with its demand and nothing the plug-in reads is used (the recording keeps road users near egos
only). The plug-in reads only the signals then and subscribes to the road users once the first ego is taken
over (``SumoSim.world_before_egos`` False, what a run does); the other side subscribes to every road user as it
departs and reads the whole world every step, as before. Both sides run the same scenario in this
process, taking turns, and must write the same recording.

    python benchmarks/warmup.py [--scenario streets/bologna_bus_lane] [--end 320] [--repeat 1]

``--end`` (simulated seconds; Bologna's egos depart at 300 s) ends each run a little after the first ego has
departed. Last line: ``ratio=X`` (reading only the signals over reading everything, the median of the turns).
"""
from __future__ import annotations

import argparse
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sumo_avoid.rollout.loop import rollout  # noqa: E402
from sumo_avoid.runs.runner import OpenRun  # noqa: E402
from sumo_avoid.core.config import ScenarioError  # noqa: E402
from sumo_avoid.scenario import spec as scenario  # noqa: E402
from _args import positive_int  # noqa: E402  (benchmarks/_args.py: this script's folder is on sys.path)


def _run(scn, whole_world: bool):
    """(wall time of the loop, s; the recording's vehicles and persons)."""
    with OpenRun(scn) as r:
        if whole_world:
            r.sim.world_before_egos = True
        t0 = time.perf_counter()
        steps = rollout(r.sim, r.stack, r.egos, r.recorder, r.n_steps)
        wall = time.perf_counter() - t0
        res = r.result(steps)
    return wall, res.traj, res.persons


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="streets/bologna_bus_lane", help="scenario path under scenarios/, no .toml")
    ap.add_argument("--end", type=float, default=320.0, help="simulated seconds each run lasts")
    ap.add_argument("--repeat", type=positive_int, default=1, help="turns per side")
    args = ap.parse_args(argv)
    try:
        scn = scenario.load(ROOT / "scenarios" / f"{args.scenario}.toml", ["output.plots=false", f"sim.duration_s={args.end}"])
    except ScenarioError as e:
        print(f"warmup.py: error: {e}", file=sys.stderr)
        return 2
    ratios = []
    for turn in range(args.repeat):
        whole, traj_w, pers_w = _run(scn, True)
        signals, traj_s, pers_s = _run(scn, False)
        same = traj_w.equals(traj_s) and pers_w.equals(pers_s)
        ratios.append(signals / whole)
        print(f"turn {turn + 1}: whole world {whole:.1f} s, signals only {signals:.1f} s (ratio {ratios[-1]:.3f}); "
              f"{len(traj_s)} vehicle and {len(pers_s)} person rows, {'the same' if same else 'DIFFERENT'}")
        if not same:
            print("the two recordings differ", file=sys.stderr)
            return 1
    print(f"ratio={statistics.median(ratios):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
