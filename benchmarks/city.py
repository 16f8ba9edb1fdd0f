"""City scale: a real district at its measured demand with 100 radar egos, against plain SUMO, with peak memory.

    python benchmarks/city.py [--duration 3600] [--begin 0] [--scale 1] [--egos 100] [--controller apf_sa]
                              [--step 0.1] [--chunk 2] [--cpu N]

The district is Bologna's Andrea Costa (``../shared/cities/bologna_acosta``, read in place, never copied): its
network with sidewalks and crossings, its measured car demand (``acosta.rou.xml``: 8,622 vehicles departing
over one hour), its bus lines and its 7,200 person trips, in the order of its ``run.sumocfg``. ``--scale``
passes SUMO's own ``--scale`` (demand multiplied by it) through ``sim.options``; the default 1 is the
measured demand. The egos are ``--egos`` of the district's own cars (type ``private``), evenly spread
over those departing in the first 80 % of the run; the plug-in drives them with ``--controller`` on
``sensor = "radar"`` with ``layers = ["traffic", "danger_time"]``, as any scenario would.

Two sides take turns on one CPU every ``--chunk`` steps (the radar benchmark's harness,
``benchmarks/radar.py``; each counts only the time it holds the baton, from SUMO loaded to closed):

* ``plain``: SUMO alone with the same command line (``sim.sumo_args``: the plug-in's options, the same
  seed and step): ``simulationStep`` only, SUMO drives the egos too. The plug-in's ``moveToXY`` cost in
  SUMO's step and the SSM device it puts on the egos (its TTC / DRAC / PET measurement) are therefore the
  plug-in's cost here.
* ``plugin``: ``runner.run`` of that scenario.

Printed: both sides' loop time, the plug-in's split into SUMO's step and its own Python, the vehicles
SUMO inserted over the run and the most in the network at once (plain side), the egos taken over, and
each side's peak resident memory (``ru_maxrss`` of its process, Python and the imports included).
Last line: ``plugin_s=X plain_s=Y ratio=Z peak_mb_plugin=A peak_mb_plain=B``.
"""
from __future__ import annotations

import argparse
import os
import pathlib
import resource
import sys
import tempfile
import xml.etree.ElementTree as ET

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import radar as bench  # noqa: E402  (the turn-taking harness)

ROOT = pathlib.Path(__file__).resolve().parents[1]
CITY = ROOT.parent / "shared" / "cities" / "bologna_acosta"
ROUTES = ("acosta.rou.xml", "persontrips.rou.xml", "acosta_busses.rou.xml")  # as run.sumocfg lists them
ADDITIONAL = ("acosta_vtypes.add.xml", "acosta_bus_stops.add.xml", "acosta_tls2.add.xml")


def pick_egos(n: int, begin_s: float, until_s: float) -> list[str]:
    """``n`` of the district's cars departing in [begin_s, until_s], evenly spread over them."""
    cars = [(float(v.get("depart")), v.get("id")) for v in ET.parse(CITY / "acosta.rou.xml").getroot().iter("vehicle")
            if v.get("type") == "private" and begin_s <= float(v.get("depart")) <= until_s]
    cars.sort()
    if len(cars) < n:
        raise SystemExit(f"only {len(cars)} cars depart between {begin_s:g} s and {until_s:g} s")
    return [cars[round(k * (len(cars) - 1) / max(n - 1, 1))][1] for k in range(n)]


def write_scenario(path: pathlib.Path, egos: list[str], a) -> None:
    files = lambda names: ", ".join(f'"{CITY / f}"' for f in names)  # noqa: E731
    ids = ", ".join(f'"{e}"' for e in egos)
    options = f'\n[sim.options]\nscale = "{a.scale:g}"\n' if a.scale != 1.0 else ""
    path.write_text(f"""name = "city_bench"
[sim]
net = "{CITY / 'acosta_peds.net.xml'}"
routes = [{files(ROUTES)}]
additional = [{files(ADDITIONAL)}]
step_s = {a.step}
begin_s = {a.begin}
duration_s = {a.duration}
seed = 1
{options}
[ego]
ids = [{ids}]
controller = "{a.controller}"
sensor = "radar"
layers = ["traffic", "danger_time"]
cruise_speed_mps = 13.89
goal_tolerance_m = 5.0
[output]
plots = false
""")


def side(which: str, toml: str, turns, profile: bool = False) -> dict:
    """One side (``plain`` or ``plugin``) in this process: its timings, counts and peak memory."""
    import libsumo

    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec as scenario
    from sumo_avoid.sumo.sim import sumo_args

    scn = scenario.load(pathlib.Path(toml))
    spec = scn.spec
    out = {}
    with bench.instrumented(turns) as t:
        if which == "plain":
            libsumo.start(sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                                    spec.sim.lateral_resolution_m, None, sumo_collisions=spec.sim.sumo_collisions,
                                    begin_s=spec.sim.begin_s, options=scn.sumo_options))
            inserted = most = 0
            try:
                for _ in range(int(round(spec.sim.duration_s / spec.sim.step_s))):  # as many as runner.run
                    libsumo.simulationStep()
                    inserted += libsumo.simulation.getDepartedNumber()
                    most = max(most, libsumo.vehicle.getIDCount())
            finally:
                libsumo.close()
            out.update(inserted=inserted, most=most)
        else:
            res = runner.run(scn)
            out.update(steps=res.steps, egos=len(res.tasks))
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {**out, "busy_s": bench.busy_s(t, turns), "sumo_step_s": t["sumo_step_s"], "peak_mb": peak_mb,
            "turns_s": turns.turns if turns is not None else []}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=3600.0, help="s simulated (default: the demand's hour)")
    ap.add_argument("--begin", type=float, default=0.0)
    ap.add_argument("--scale", type=float, default=1.0, help="SUMO's --scale of the demand (default 1: as measured)")
    ap.add_argument("--egos", type=int, default=100)
    ap.add_argument("--controller", default="apf_sa")
    ap.add_argument("--step", type=float, default=0.1)
    ap.add_argument("--chunk", type=int, default=2)
    ap.add_argument("--cpu", type=int, default=None)
    a = ap.parse_args(argv)
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    egos = pick_egos(a.egos, a.begin, a.begin + 0.8 * a.duration)
    with tempfile.TemporaryDirectory() as tmp:
        toml = pathlib.Path(tmp) / "city.toml"
        write_scenario(toml, egos, a)
        cpu = a.cpu if a.cpu is not None else max(os.sched_getaffinity(0))
        r = bench.interleaved(toml, cpu, a.chunk, int(round(a.duration / a.step)), False, run_side=side)
    pl, pg = r["plain"], r["plugin"]
    print(bench._line(pl, pg))
    print(bench.paired_turns(pl["turns_s"], pg["turns_s"]))
    print(f"Bologna Andrea Costa, {a.begin:g}-{a.begin + a.duration:g} s, step {a.step:g} s, scale {a.scale:g}: "
          f"{pl['inserted']} vehicles inserted (at most {pl['most']} at once), {pg['egos']} of {a.egos} egos taken over, "
          f"controller {a.controller}, {pg['steps']} steps (taking turns every "
          f"{a.chunk} steps on cpu {cpu})")
    print(f"peak memory: plug-in {pg['peak_mb']:.0f} MB, plain SUMO {pl['peak_mb']:.0f} MB (resident, whole process)")
    print(f"plugin_s={pg['busy_s']:.2f} plain_s={pl['busy_s']:.2f} ratio={pg['busy_s'] / pl['busy_s']:.2f} "
          f"peak_mb_plugin={pg['peak_mb']:.0f} peak_mb_plain={pl['peak_mb']:.0f}")


if __name__ == "__main__":
    main()
