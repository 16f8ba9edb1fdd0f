"""What makes SUMO's own step slower when the plug-in drives some vehicles? Two ways of driving the
same egos, timed against each other with the radar benchmark's turn-taking (one pinned CPU, turns
every ``--chunk`` steps; ``benchmarks/radar.py``):

    python benchmarks/sumo_step.py A B [--steps 150] [--chunk 2] [--net single|segments] [--no-sumo-collisions]

with A, B among

* ``plain``:    SUMO drives everybody (as ``plain_s`` in benchmarks/radar.py);
* ``setspeed``: egos with speed mode 32 / lane-change mode 0 held at 8 m/s by ``setSpeed`` (SUMO moves them);
* ``move``:     the same egos placed 0.8 m (8 m/s x 0.1 s) ahead along their heading by
  ``moveToXY(keepRoute=2)`` + ``setPreviousSpeed``, as the plug-in's actuator does;
* ``move_numpy``: ``move`` plus ~12 ms of numpy work per step outside SUMO (a stand-in for the
  plug-in's own Python: does it slow SUMO's next step by evicting its data from the caches?).

Only the time inside ``simulationStep`` is compared. Last line: ``A_s=X B_s=Y ratio=B/A``.
"""
from __future__ import annotations

import argparse
import math
import os
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import radar as bench  # noqa: E402  (the traffic and the turn-taking harness)

SIDES = ("plain", "setspeed", "move", "move_numpy")


def _numpy_work(state):
    import numpy as np

    x = state
    for _ in range(40):
        x = np.sqrt(x * x + 1.0) - 1.0
    np.sort(np.random.default_rng(1).random(200_000))


def side(which: str, toml: str, turns, profile: bool = False) -> dict:
    import libsumo
    import numpy as np

    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(pathlib.Path(toml))
    spec = scn.spec
    egos = list(spec.ego.ids)
    junk = np.random.default_rng(0).random((400, 27, 8))
    with bench.instrumented(turns) as t:
        bench.start_sumo(scn)
        libsumo.simulationStep()  # everybody inserted
        if which != "plain":
            for v in egos:
                libsumo.vehicle.setSpeedMode(v, 32)
                libsumo.vehicle.setLaneChangeMode(v, 0)
        for _ in range(int(round(spec.sim.duration_s / spec.sim.step_s)) - 1):
            if which == "setspeed":
                for v in egos:
                    libsumo.vehicle.setSpeed(v, 8.0)
            elif which in ("move", "move_numpy"):
                if which == "move_numpy":
                    _numpy_work(junk)
                for v in egos:
                    x, y = libsumo.vehicle.getPosition(v)
                    a = libsumo.vehicle.getAngle(v)
                    h = math.radians(90.0 - a)
                    libsumo.vehicle.moveToXY(v, "", -1, x + 0.8 * math.cos(h), y + 0.8 * math.sin(h), angle=a,
                                             keepRoute=2)
                    libsumo.vehicle.setPreviousSpeed(v, 8.0)
            libsumo.simulationStep()
        libsumo.close()
    return {"busy_s": bench.busy_s(t, turns), "sumo_step_s": t["sumo_step_s"]}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", choices=SIDES)
    ap.add_argument("b", choices=SIDES)
    ap.add_argument("--steps", type=int, default=150)
    ap.add_argument("--chunk", type=int, default=2)
    ap.add_argument("--net", choices=sorted(bench.NETS), default="single")
    ap.add_argument("--no-sumo-collisions", action="store_true", help="SUMO's own collision check off on both sides")
    a = ap.parse_args(argv)
    if a.a == a.b:
        ap.error("two different sides")
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        net, segment_m = bench.NETS[a.net]
        egos = bench.write_routes(tmp / "bench.rou.xml", 1000, 100, segment_m=segment_m)
        bench.write_scenario(tmp / "bench.toml", tmp / "bench.rou.xml", egos, a.steps / 10, "scripted",
                             not a.no_sumo_collisions, net)
        r = bench.interleaved(tmp / "bench.toml", max(os.sched_getaffinity(0)), a.chunk, a.steps, False,
                              sides=(a.a, a.b), run_side=side)
    sa, sb = r[a.a]["sumo_step_s"], r[a.b]["sumo_step_s"]
    print(f"{a.a}_s={sa:.2f} {a.b}_s={sb:.2f} ratio={sb / sa:.3f}")


if __name__ == "__main__":
    main()
