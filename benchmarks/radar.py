"""Radar-equipped egos among ~1,000 SUMO vehicles: the plug-in's wall time vs plain SUMO's.

    python benchmarks/radar.py [--vehicles 1000] [--egos 100] [--duration 30] [--controller scripted]
                               [--net single|segments] [--chunk 2] [--cpu N] [--sequential [--repeat 3]]
                               [--no-sumo-collisions] [--profile]

Traffic: ``--vehicles`` cars on nets/highway.net.xml (3 lanes x 4 km, one edge; ``--net segments``:
the same road as 16 edges of 250 m, nets/highway_segments.net.xml), all inserted at t = 0,
11.5 m apart in every lane, at 8 m/s; every (vehicles/egos)-th one (from 400 m before the road end
back) is an ego. Same route file, seed and SUMO options on both sides:

* ``plain_s``: SUMO drives everybody, and each step every ego is moved by ``moveToXY`` (edge and lane as
  hints, ``keepRoute=1``) + ``setPreviousSpeed`` where its speed takes it along its heading (speed mode 32,
  lane-change mode 0): the plug-in side's moveToXY work and its cost in SUMO's step (docs/radar.md).
  ``--plain sumo``: the old plain side, simulationStep() only; ``--plain moved_ssm``: moved, and SUMO's SSM
  device on the egos as in the plug-in's run (``sumo_avoid/sumo/ssm_device.py``), its cost left out.
* ``plugin_s``: runner.run() with ``ego.sensor = "radar"``, ``ego.layers = ["traffic", "danger_time"]`` and the
  given controller (default ``scripted``: constant speed, so the time is the plug-in's machinery
  (snapshot, radar, tracker, danger-time layer, actuator, moveToXY, recorder) rather than a
  controller's).

Both count the simulation loop only: from SUMO loaded (``libsumo.start`` returned) to
``libsumo.close``; network and route loading are excluded on both sides.

**How the two are timed (default: taking turns).** These 2-core VMs are shared: a fixed Python loop
on one pinned vCPU took anywhere from 0.34 s to 0.69 s within a minute, and the two vCPUs differ
from each other by as much (measured 2026-11-23, ``docs/radar.md``). Runs timed one after the other
(``--sequential``) therefore compare two different machines: the same plug-in run gave 64 s and
81 s. By default the two sides run as two processes pinned to the **same** CPU that take turns every
``--chunk`` steps (a baton of two semaphores; the waiting side sleeps); each side counts only the
time it holds the baton (the hand-over counts as waiting). Both see the same machine within a
fraction of a second (2 steps), and the per-side SUMO step times are comparable as well. BLAS threads are limited to one in both processes (a
spinning BLAS thread of one side would otherwise take CPU from the other).

Every line splits the plug-in's time into SUMO's ``simulationStep`` and the plug-in's own Python.
``--no-sumo-collisions`` runs both sides without SUMO's own collision check (its sublane check
compares every pair of vehicles on a lane; a lane holding a vehicle moved by ``moveToXY`` is
checked once more per step). ``--profile`` prints a cProfile summary of the plug-in side. With
turns, one more line gives the median of the paired per-turn ratios (plug-in turn k / plain turn
k, the same steps): a burst of load from another tenant that hits a few turns of one side moves
the sums but hardly the median. Last line: ``plugin_s=X plain_s=Y ratio=Z`` (the sums).
"""
from __future__ import annotations

import argparse
import contextlib
import cProfile
import ctypes
import io
import math
import multiprocessing as mp
import os
import pathlib
import pstats
import signal
import sys
import tempfile
import time
from _args import positive_int  # noqa: E402  (benchmarks/_args.py: this script's folder is on sys.path)

ROOT = pathlib.Path(__file__).resolve().parents[1]
NETS = {"single": (ROOT / "nets" / "highway.net.xml", None),  # one 4000 m edge
        "segments": (ROOT / "nets" / "highway_segments.net.xml", 250.0)}  # 16 edges of 250 m


def write_routes(path: pathlib.Path, n: int, n_ego: int, spacing_m: float = 11.5, speed: float = 8.0,
                 segment_m: float | None = None) -> list[str]:
    """The benchmark traffic; ``segment_m``: the road is cut into edges hw0, hw1, ... of that length
    (nets/highway_segments.net.xml), each vehicle departs on the edge it stands on."""
    lines = ['<routes>',
             '  <vType id="car" vClass="passenger" length="4.5" width="1.8" maxSpeed="12" sigma="0"/>',
             '  <vType id="ego_car" vClass="passenger" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="40" sigma="0"/>']
    n_seg = int(round(4000.0 / segment_m)) if segment_m else 1
    if segment_m:
        lines += [f'  <route id="r{k}" edges="{" ".join(f"hw{j}" for j in range(k, n_seg))}"/>' for k in range(n_seg)]
    else:
        lines.append('  <route id="r0" edges="hw"/>')
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
            seg = min(int(pos // segment_m), n_seg - 1) if segment_m else 0
            lines.append(f'  <vehicle id="{vid}" type="{"ego_car" if is_ego else "car"}" route="r{seg}" depart="0" '
                         f'departLane="{lane}" departPos="{pos - seg * (segment_m or 0.0):.1f}" departSpeed="{speed}" '
                         'insertionChecks="none"/>')
            k += 1
    lines.append('</routes>')
    path.write_text("\n".join(lines) + "\n")
    return egos


def write_scenario(path: pathlib.Path, routes: pathlib.Path, egos: list[str], duration: float, controller: str,
                   sumo_collisions: bool = True, net: pathlib.Path = NETS["single"][0]) -> None:
    ids = ", ".join(f'"{e}"' for e in egos)
    path.write_text(f"""name = "radar_bench"
[sim]
net = "{net}"
routes = ["{routes}"]
duration_s = {duration}
seed = 1
sumo_collisions = {str(sumo_collisions).lower()}
[ego]
ids = [{ids}]
controller = "{controller}"
sensor = "radar"
layers = ["traffic", "danger_time"]
cruise_speed_mps = 8.0
[controllers.scripted]
speed_mps = 8.0
[output]
plots = false
""")


class Turns:
    """Two processes on one CPU take turns every ``chunk`` steps; ``waited`` is the time this side
    slept waiting for its turn (excluded from its timing)."""

    def __init__(self, mine, theirs, done, me: int, chunk: int, counter):
        self.mine, self.theirs, self.done, self.me, self.chunk = mine, theirs, done, me, chunk
        self.counter = counter
        self.steps = 0
        self.waited = 0.0
        self.turns: list[float] = []  # busy time of each of this side's turns, s
        self._turn_t0: float | None = None

    def wait_turn(self, handing_over: bool = False) -> None:
        """Sleep until it is this side's turn. ``handing_over``: give the other side its turn first;
        the release is timed as waiting too, because on one CPU the woken side may run at once,
        inside the release call (measured: 1.2 ms per release on average)."""
        t0 = time.perf_counter()
        self._end_turn(t0)
        if handing_over:
            self.theirs.release()
        self.mine.acquire()
        self._turn_t0 = time.perf_counter()
        self.waited += self._turn_t0 - t0

    def _end_turn(self, now: float) -> None:
        if self._turn_t0 is not None:
            self.turns.append(now - self._turn_t0)
            self._turn_t0 = None

    def stepped(self) -> None:
        self.steps += 1
        self.counter.value = self.steps
        if self.steps % self.chunk == 0 and not self.done[1 - self.me]:
            self.wait_turn(handing_over=True)

    def finish(self) -> None:
        self._end_turn(time.perf_counter())
        self.done[self.me] = 1
        self.theirs.release()


@contextlib.contextmanager
def instrumented(turns: Turns | None):
    """Wrap libsumo.start / simulationStep / close (sim.py calls them through the module, so this
    sees the plug-in's calls too): the loop's wall time from SUMO loaded to close, the time inside
    simulationStep, and, with ``turns``, the baton between the two sides."""
    import libsumo

    t = {"sumo_step_s": 0.0, "t0": None, "t1": None}
    orig = libsumo.start, libsumo.simulationStep, libsumo.close

    def start(*a, **k):
        out = orig[0](*a, **k)
        t["t0"] = time.perf_counter()  # the first wait for the baton is in turns.waited, like all others
        if turns is not None:
            turns.wait_turn()
        return out

    def step(*a):
        t0 = time.perf_counter()
        try:
            return orig[1](*a)
        finally:
            t["sumo_step_s"] += time.perf_counter() - t0
            if turns is not None:
                turns.stepped()

    def close(*a):
        if t["t1"] is None:
            t["t1"] = time.perf_counter()
            if turns is not None:
                turns.finish()
        return orig[2](*a)

    libsumo.start, libsumo.simulationStep, libsumo.close = start, step, close
    try:
        yield t
    finally:
        libsumo.start, libsumo.simulationStep, libsumo.close = orig


def start_sumo(scn, ssm_dir: pathlib.Path | None = None) -> None:
    """Start plain SUMO with the scenario's options, exactly as runner.run does (sim.sumo_args); ``ssm_dir``:
    with SUMO's SSM device on the egos as well, its file there (the plug-in's runs measure with it)."""
    import libsumo

    from sumo_avoid.sumo.sim import sumo_args
    from sumo_avoid.sumo.ssm_device import SsmRequest

    spec = scn.spec
    ssm = SsmRequest(tuple(spec.ego.ids), ssm_dir / "ssm.xml") if ssm_dir is not None else None
    libsumo.start(sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                            spec.sim.lateral_resolution_m, None, sumo_collisions=spec.sim.sumo_collisions, ssm=ssm))


def move_egos(ids, step_s: float, first: bool) -> None:
    """The plain side's moveToXY work: each ego moved where its speed takes it along its heading, on its lane."""
    import libsumo

    c = libsumo.constants
    if first:
        for vid in ids:
            libsumo.vehicle.subscribe(vid, [c.VAR_POSITION, c.VAR_ANGLE, c.VAR_SPEED, c.VAR_ROAD_ID, c.VAR_LANE_INDEX])
            libsumo.vehicle.setSpeedMode(vid, 32)
            libsumo.vehicle.setLaneChangeMode(vid, 0)
    res = libsumo.vehicle.getAllSubscriptionResults()
    for vid in ids:
        r = res[vid]
        (x, y), a, v = r[c.VAR_POSITION], r[c.VAR_ANGLE], r[c.VAR_SPEED]
        h = math.radians(a)
        libsumo.vehicle.moveToXY(vid, r[c.VAR_ROAD_ID], r[c.VAR_LANE_INDEX], x + v * step_s * math.sin(h),
                                 y + v * step_s * math.cos(h), angle=a, keepRoute=1)
        libsumo.vehicle.setPreviousSpeed(vid, v)


def busy_s(t: dict, turns: Turns | None) -> float:
    """The loop's wall time without the waits for the baton."""
    return t["t1"] - t["t0"] - (turns.waited if turns is not None else 0.0)


def side(which: str, toml: str, turns: Turns | None, profile: bool = False) -> dict:
    """Run one side (``plain`` or ``plugin``) of the benchmark in this process; its timings."""
    import libsumo

    from sumo_avoid.runs import outputs as evaluate
    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(pathlib.Path(toml))
    spec = scn.spec
    out = {}
    with instrumented(turns) as t:
        if which.startswith("plain"):
            tmp = tempfile.TemporaryDirectory() if which == "plain_ssm" else None
            start_sumo(scn, pathlib.Path(tmp.name) if tmp else None)
            try:
                for k in range(int(round(spec.sim.duration_s / spec.sim.step_s))):  # as many as runner.run
                    if which != "plain_sumo" and k:
                        move_egos(spec.ego.ids, spec.sim.step_s, k == 1)
                    libsumo.simulationStep()
            finally:
                libsumo.close()
        else:
            prof = cProfile.Profile() if profile else None
            if prof:
                prof.enable()
            res = runner.run(scn)
            if prof:
                prof.disable()
                s = io.StringIO()
                pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(18)
                out["profile"] = s.getvalue()
            m = evaluate.compute(res)
            out.update(steps=res.steps, collisions=m["collisions"], radar_brakes=m["radar_brakes"],
                       radar_warnings=m["radar_warnings"])
    return {**out, "busy_s": busy_s(t, turns), "sumo_step_s": t["sumo_step_s"],
            "turns_s": turns.turns if turns is not None else []}


def _die_with_parent(parent: int) -> None:
    """Linux: this side gets SIGTERM when the harness dies (``kill`` of the harness alone left both sides running
    on, a CPU held for half an hour); elsewhere nothing."""
    with contextlib.suppress(Exception):
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # died before the call
        os._exit(1)


def _child(which, me, toml, cpu, sems, done, chunk, counter, profile, queue, run_side, parent) -> None:
    _die_with_parent(parent)
    os.sched_setaffinity(0, {cpu})
    turns = Turns(sems[me], sems[1 - me], done, me, chunk, counter)
    try:
        queue.put((which, run_side(which, toml, turns, profile)))
    except BaseException as e:  # report, and never leave the other side waiting for the baton
        turns.finish()
        queue.put((which, {"error": f"{type(e).__name__}: {e}"}))


def interleaved(toml: pathlib.Path, cpu: int, chunk: int, n_steps: int, profile: bool,
                sides=("plain", "plugin"), run_side=side) -> dict:
    """Run two sides (``run_side(name, toml, turns, profile)``) taking turns on ``cpu``."""
    ctx = mp.get_context("spawn")  # fresh interpreters: the BLAS thread limit set in main() applies
    sems = (ctx.Semaphore(0), ctx.Semaphore(0))
    done = ctx.Array("i", 2)
    counters = (ctx.Value("i", 0), ctx.Value("i", 0))
    queue = ctx.Queue()
    procs = [ctx.Process(target=_child, args=(w, k, str(toml), cpu, sems, done, chunk, counters[k],
                                              profile and k == 1, queue, run_side, os.getpid()))
             for k, w in enumerate(sides)]
    for p in procs:
        p.start()
    sems[1].release()  # the plug-in side has the first turn (whichever has loaded SUMO first waits)
    results, t0 = {}, time.perf_counter()
    def progress(end=""):
        print(f"\r  steps: {sides[0]} {counters[0].value}/{n_steps}  {sides[1]} {counters[1].value}/{n_steps}  "
              f"wall {time.perf_counter() - t0:5.0f} s", end=end, file=sys.stderr, flush=True)

    while len(results) < 2:
        with contextlib.suppress(Exception):
            which, r = queue.get(timeout=2.0)
            results[which] = r
            continue
        dead = [w for w, p in zip(sides, procs) if p.exitcode not in (None, 0)]
        if dead or (not any(p.is_alive() for p in procs) and queue.empty()):
            for p in procs:  # the other side may be waiting for a baton that never comes
                p.terminate()
            raise RuntimeError(f"benchmark process(es) {dead} died (exit codes {[p.exitcode for p in procs]})")
        progress()
    progress("\n")
    for p in procs:
        p.join()
    for which, r in results.items():
        if "error" in r:
            raise RuntimeError(f"{which} side failed: {r['error']}")
    return results


def _line(plain: dict, plugin: dict) -> str:
    own = plugin["busy_s"] - plugin["sumo_step_s"]
    return (f"  plain {plain['busy_s']:.2f} s  plug-in {plugin['busy_s']:.2f} s = SUMO step {plugin['sumo_step_s']:.2f} s "
            f"+ plug-in's own {own:.2f} s   (SUMO step ratio {plugin['sumo_step_s'] / plain['sumo_step_s']:.3f}, "
            f"own / plain {own / plain['busy_s']:.3f})")


def paired_turns(plain: list[float], plugin: list[float]) -> str:
    """The two sides' turns cover the same steps (turn k: steps k*chunk ...), so plug-in turn k /
    plain turn k is a paired ratio; its median is insensitive to a burst of load from elsewhere
    that hits a few turns of one side (the sums above are not). The last turn may be partial: left out."""
    import numpy as np

    k = min(len(plain), len(plugin)) - 1
    if k < 1:
        return "  paired turns: too few"
    r = np.array(plugin[:k]) / np.array(plain[:k])
    q1, med, q3 = np.percentile(r, [25, 50, 75])
    return f"  paired turns ({k}, same steps): plug-in / plain median {med:.3f}, quartiles {q1:.3f}-{q3:.3f}"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vehicles", type=int, default=1000)
    ap.add_argument("--egos", type=int, default=100)
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--controller", default="scripted")
    ap.add_argument("--net", choices=sorted(NETS), default="single",
                    help="single: one 4000 m edge (the issue's benchmark); segments: the same road as 16 edges of 250 m")
    ap.add_argument("--chunk", type=int, default=2, help="steps per turn (default 2 = 0.2 s simulated)")
    ap.add_argument("--cpu", type=int, default=None, help="CPU both sides are pinned to (default: the last allowed)")
    ap.add_argument("--sequential", action="store_true", help="the old way: one after the other in this process")
    ap.add_argument("--repeat", type=positive_int, default=3, help="--sequential: alternate N times, keep each's minimum")
    ap.add_argument("--no-sumo-collisions", action="store_true", help="SUMO's own collision check off on both sides")
    ap.add_argument("--plain", choices=("moved", "sumo", "moved_ssm"), default="moved",
                    help="moved: the plain side moves the egos by moveToXY too (default); sumo: SUMO moves them; "
                         "moved_ssm: moved, and SUMO's SSM device on the egos as in the plug-in's run")
    ap.add_argument("--profile", action="store_true")
    a = ap.parse_args(argv)
    plain_side = {"moved": "plain", "sumo": "plain_sumo", "moved_ssm": "plain_ssm"}[a.plain]
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        net, segment_m = NETS[a.net]
        egos = write_routes(tmp / "bench.rou.xml", a.vehicles, a.egos, segment_m=segment_m)
        write_scenario(tmp / "bench.toml", tmp / "bench.rou.xml", egos, a.duration, a.controller,
                       not a.no_sumo_collisions, net)
        n_steps = int(round(a.duration / 0.1))
        if a.sequential:
            plain_s = plugin_s = float("inf")
            for _ in range(max(a.repeat, 1)):
                pl = side(plain_side, str(tmp / "bench.toml"), None)
                pg = side("plugin", str(tmp / "bench.toml"), None, a.profile)
                plain_s, plugin_s = min(plain_s, pl["busy_s"]), min(plugin_s, pg["busy_s"])
                print(_line(pl, pg), flush=True)
            how = f"sequential, best of {max(a.repeat, 1)}"
        else:
            cpu = a.cpu if a.cpu is not None else max(os.sched_getaffinity(0))
            r = interleaved(tmp / "bench.toml", cpu, a.chunk, n_steps, a.profile, sides=(plain_side, "plugin"))
            pl, pg = r[plain_side], r["plugin"]
            plain_s, plugin_s = pl["busy_s"], pg["busy_s"]
            print(_line(pl, pg), flush=True)
            print(paired_turns(pl["turns_s"], pg["turns_s"]), flush=True)
            how = f"taking turns every {a.chunk} steps on cpu {cpu}"
        print(f"vehicles {a.vehicles}  egos {len(egos)}  steps {pg['steps']}  controller {a.controller}  "
              f"collisions {pg['collisions']}  radar_brakes {pg['radar_brakes']}  radar_warnings {pg['radar_warnings']}"
              f"  net {a.net}  plain side: {a.plain}  ({how})")
        if "profile" in pg:
            print(pg["profile"])
    print(f"plugin_s={plugin_s:.2f} plain_s={plain_s:.2f} ratio={plugin_s / plain_s:.2f}")


if __name__ == "__main__":
    main()
