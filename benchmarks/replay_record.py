"""What recording a run for watching costs: the files ``sumo-avoid replay`` and the viewer need
beyond a run's other outputs (``replay.json``, ``signals.csv``; the signal states were already
recorded each step for the rule metrics, so the added cost is writing them), against the run's wall
time (its loop and set-up, ``timings.json``'s ``total_s``, plus writing its other outputs).

    python benchmarks/replay_record.py [--scenario overtaking --scenario signal_crossing_right ...] [--repeat 5]

Each scenario runs once in this process (real libsumo); the replay files are written ``--repeat``
times into a temporary folder and the median is taken. Last line: ``max_share=X`` (the largest
share of a run's wall time over the scenarios; the issue allows 0.05).
"""
from __future__ import annotations

import argparse
import pathlib
import statistics
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sumo_avoid.runs import outputs, runner  # noqa: E402
from sumo_avoid.core.config import ScenarioError  # noqa: E402
from sumo_avoid.scenario import spec as scenario  # noqa: E402
from _args import positive_int  # noqa: E402  (benchmarks/_args.py: this script's folder is on sys.path)

DEFAULT = ("overtaking", "streets/signal_crossing_right")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", action="append", default=None, help="scenario path under scenarios/, no .toml")
    ap.add_argument("--repeat", type=positive_int, default=5)
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args(argv)
    shares = []
    for name in args.scenario or DEFAULT:
        try:
            scn = scenario.load(ROOT / "scenarios" / f"{name}.toml", args.overrides)
        except ScenarioError as e:
            print(f"replay_record.py: error: {e}", file=sys.stderr)
            return 2
        res = runner.run(scn)
        with tempfile.TemporaryDirectory(prefix="replay-bench-") as tmp:
            t0 = time.perf_counter()
            outputs.write_outputs(res, pathlib.Path(tmp) / "all", plots=False)
            write_all_s = time.perf_counter() - t0
            times = []
            for i in range(args.repeat):
                d = pathlib.Path(tmp) / f"r{i}"
                d.mkdir()
                t0 = time.perf_counter()
                outputs.write_replay_files(res, d)
                times.append(time.perf_counter() - t0)
        replay_s = statistics.median(times)
        run_s = res.timings["total_s"] + write_all_s - replay_s
        shares.append(replay_s / run_s)
        signals = 0 if res.signals is None else len(res.signals)
        print(f"{name}: run {run_s:.2f} s (sim {res.sim_time_s:.0f} s, {len(res.traj)} rows, {signals} signal "
              f"changes); replay files {1000 * replay_s:.2f} ms = {100 * shares[-1]:.3f} % of the run")
    print(f"max_share={max(shares):.5f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
