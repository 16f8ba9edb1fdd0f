"""Radar-equipped egos among ~1,000 SUMO vehicles: the plug-in's wall time vs plain SUMO's.

    python benchmarks/radar.py [--vehicles 1000] [--egos 100] [--duration 30] [--controller scripted]
                               [--repeat 1] [--profile]

Traffic: ``--vehicles`` cars on nets/highway.net.xml (3 lanes x 4 km), all inserted at t = 0,
11.5 m apart in every lane, at 8 m/s; every (vehicles/egos)-th one (from 400 m before the road end back) is an ego. Same route file,
seed and SUMO options for both runs, in this process, one after the other:

* ``plain_s``: SUMO alone drives everybody (egos too): libsumo.simulationStep() only.
* ``plugin_s``: runner.run() with ``ego.sensor = "radar"``, ``ego.safety = "danger_time"`` and the
  given controller (default ``scripted``: constant speed, so the time is the plug-in's machinery
  (snapshot, radar, danger-time layer, actuator, moveToXY, recorder) rather than a controller's).

Both exclude SUMO start-up (network and route loading). ``--repeat N`` (default 3) alternates the
two N times and keeps each one's fastest time (the least disturbed by other load, as ``timeit``
does). Every plug-in run is split into the time inside SUMO's ``simulationStep`` and the rest (the
plug-in's own Python: snapshot read, radar, tracker, layer, actuator, recorder), so each line shows
where the time went. ``--no-sumo-collisions`` runs both sides without SUMO's own collision check
(its sublane check compares every pair of vehicles on a lane, and each lane holding a vehicle moved
by ``moveToXY`` gets one extra check per step). ``--profile`` prints a cProfile summary of the
plug-in run. Last line: ``plugin_s=X plain_s=Y ratio=Z``.
"""
from __future__ import annotations

import argparse
import contextlib
import cProfile
import io
import pathlib
import pstats
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
NET = ROOT / "nets" / "highway.net.xml"


def write_routes(path: pathlib.Path, n: int, n_ego: int, spacing_m: float = 11.5, speed: float = 8.0) -> list[str]:
    every = max(n // max(n_ego, 1), 1)
    lines = ['<routes>',
             '  <vType id="car" vClass="passenger" length="4.5" width="1.8" maxSpeed="12" sigma="0"/>',
             '  <vType id="ego_car" vClass="passenger" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="40" sigma="0"/>',
             '  <route id="r" edges="hw"/>']
    egos, k = [], 0
    per_lane = -(-n // 3)
    every = max((n - 3 * int(400 / spacing_m)) // max(n_ego, 1), 1)
    for i in range(per_lane):
        for lane in range(3):
            if k == n:
                break
            pos = 3990.0 - i * spacing_m
            # egos start >= 400 m from the road end so none leaves the network during the run
            is_ego = k % every == 0 and len(egos) < n_ego and pos < 3590.0
            vid = f"ego{len(egos)}" if is_ego else f"v{k}"
            egos += [vid] if is_ego else []
            lines.append(f'  <vehicle id="{vid}" type="{"ego_car" if is_ego else "car"}" route="r" depart="0" '
                         f'departLane="{lane}" departPos="{pos:.1f}" departSpeed="{speed}" insertionChecks="none"/>')
            k += 1
    lines.append('</routes>')
    path.write_text("\n".join(lines) + "\n")
    return egos


def write_scenario(path: pathlib.Path, routes: pathlib.Path, egos: list[str], duration: float, controller: str,
                   sumo_collisions: bool = True) -> None:
    ids = ", ".join(f'"{e}"' for e in egos)
    path.write_text(f"""name = "radar_bench"
[sim]
net = "{NET}"
routes = ["{routes}"]
duration_s = {duration}
seed = 1
sumo_collisions = {str(sumo_collisions).lower()}
[ego]
ids = [{ids}]
controller = "{controller}"
sensor = "radar"
safety = "danger_time"
cruise_speed_mps = 8.0
[controllers.scripted]
speed_mps = 8.0
[output]
plots = false
""")


def plain(scn, sumo_collisions: bool = True) -> float:
    import libsumo

    from sumo_avoid.sim import sumo_args

    spec = scn.spec
    args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                     spec.sim.lateral_resolution_m, None, sumo_collisions=sumo_collisions)
    libsumo.start(args)
    try:
        t0 = time.perf_counter()
        for _ in range(int(round(spec.sim.duration_s / spec.sim.step_s)) + 1):
            libsumo.simulationStep()
        return time.perf_counter() - t0
    finally:
        libsumo.close()


@contextlib.contextmanager
def timed_sumo_steps():
    """Accumulate the wall time spent inside libsumo.simulationStep (sim.py calls it through the
    module attribute, so wrapping it here sees every step of the plug-in run)."""
    import libsumo

    total = [0.0]
    original = libsumo.simulationStep

    def step(*args):
        t0 = time.perf_counter()
        try:
            return original(*args)
        finally:
            total[0] += time.perf_counter() - t0

    libsumo.simulationStep = step
    try:
        yield total
    finally:
        libsumo.simulationStep = original


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vehicles", type=int, default=1000)
    ap.add_argument("--egos", type=int, default=100)
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--controller", default="scripted")
    ap.add_argument("--repeat", type=int, default=3, help="alternate plain/plug-in runs N times, keep each's minimum")
    ap.add_argument("--no-sumo-collisions", action="store_true", help="SUMO's own collision check off on both sides")
    ap.add_argument("--profile", action="store_true")
    a = ap.parse_args(argv)
    from sumo_avoid import evaluate, runner, scenario

    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        egos = write_routes(tmp / "bench.rou.xml", a.vehicles, a.egos)
        write_scenario(tmp / "bench.toml", tmp / "bench.rou.xml", egos, a.duration, a.controller,
                       not a.no_sumo_collisions)
        scn = scenario.load(tmp / "bench.toml")
        plain_s = plugin_s = float("inf")
        for _ in range(max(a.repeat, 1)):
            this_plain = plain(scn, scn.spec.sim.sumo_collisions)
            plain_s = min(plain_s, this_plain)
            prof = cProfile.Profile() if a.profile else None
            with timed_sumo_steps() as sumo_s:
                if prof:
                    prof.enable()
                res = runner.run(scn)
                if prof:
                    prof.disable()
            loop_s = res.timings["loop_s"]
            plugin_s = min(plugin_s, loop_s)
            print(f"  plain {this_plain:.2f} s  plug-in {loop_s:.2f} s = SUMO step {sumo_s[0]:.2f} s "
                  f"+ plug-in's own {loop_s - sumo_s[0]:.2f} s", flush=True)
        m = evaluate.compute(res)
        print(f"vehicles {a.vehicles}  egos {len(egos)}  steps {res.steps}  controller {a.controller}  "
              f"collisions {m['collisions']}  radar_brakes {m['radar_brakes']}  radar_warnings {m['radar_warnings']}")
        if prof:
            s = io.StringIO()
            pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(18)
            print(s.getvalue())
    print(f"plugin_s={plugin_s:.2f} plain_s={plain_s:.2f} ratio={plugin_s / plain_s:.2f}")


if __name__ == "__main__":
    main()
