"""One scenario, one run: start SUMO, set the scene up, assemble the plug-ins, roll out, record.

``run(scenario)`` returns a :class:`~sumo_avoid.rollout.result.RunResult`; metrics are computed
from its recording afterwards (:mod:`sumo_avoid.metrics`) and never feed back into the run.
"""
from __future__ import annotations

import pathlib
import tempfile
import time

from tqdm import tqdm

from sumo_avoid.core.config import FieldError, ScenarioError
from sumo_avoid.road.network import Road
from sumo_avoid.road.walls import square
from sumo_avoid.rollout.assemble import assemble, context, controller_for
from sumo_avoid.rollout.egos import EgoBook
from sumo_avoid.rollout.loop import rollout
from sumo_avoid.rollout.recorder import Recorder
from sumo_avoid.rollout.result import RunResult, Scene
from sumo_avoid.rollout.spawn import ArenaSpawn, StaticObstacles
from sumo_avoid.scenario.spec import sumo_load_error
from sumo_avoid.sumo.sim import SumoSim, SumoStartError, SumoStepError, sumo_args
from sumo_avoid.sumo.ssm_device import SsmParams, SsmRequest, read_conflicts


class Progress:
    """A tqdm bar over simulated seconds (the loop's callback)."""

    def __init__(self, duration_s: float):
        self.bar = tqdm(total=round(duration_s, 3), unit="s sim", leave=True, dynamic_ncols=True,
                        bar_format="  {l_bar}{bar}| {n:.0f}/{total:.0f} s sim [{elapsed}<{remaining}]")

    def on_step(self, snap, n_steps: int) -> None:
        self.bar.update(max(0.0, min(snap.time_s, self.bar.total) - self.bar.n))

    def on_end(self) -> None:
        self.bar.close()


def never_departed_error(scn, missing: list[str], time_s: float, waiting) -> ScenarioError:
    """An ego that never departed within the run is bad input (a depart time after the end, or a
    vehicle SUMO could not insert): one line naming the first such ego and why, as far as SUMO tells."""
    vid = missing[0]
    ids = scn.spec.ego.ids
    key = f"ego.ids[{ids.index(vid)}]" if vid in ids else "arena"
    why = ("SUMO could not insert it: still waiting for room to depart" if vid in waiting else
           "its depart time is later, or SUMO dropped it")
    more = f"; also {', '.join(repr(v) for v in missing[1:])}" if len(missing) > 1 else ""
    return ScenarioError(str(scn.path), key, f"egos that depart within the run: '{vid}' never departed by "
                                             f"t={time_s:.1f} s ({why}){more}", show_got=False)


def run(scn, *, log_file=None, progress: bool = False, callbacks=()) -> RunResult:
    """Run one scenario. Raises :class:`ScenarioError` (one line, naming the scenario file and key)
    for input found bad only once SUMO runs: files SUMO cannot load (at the start or when it gets to
    an element, e.g. an invalid departLane), a goal edge not on an ego's route, an ego that never departed.
    ``callbacks``: more rollout callbacks (``on_step``, ``on_end``) beside the progress bar."""
    spec = scn.spec
    t_start = time.perf_counter()
    arena = spec.arena
    road = Road.from_net_file(scn.net_file)
    walls = square(arena.origin, arena.size_m) if arena is not None else None
    obstacles = tuple(o.polygon for o in spec.obstacles)
    ctx = context(scn, spec.sim.step_s, road, walls, obstacles)  # steering limits and tables: assemble.context
    controller = controller_for(scn, ctx)
    recorder = Recorder(spec.output.record_radius_m)
    hooks = [StaticObstacles(spec.obstacles, obstacles)] + ([ArenaSpawn(arena, walls, obstacles, ctx.rng(1))] if arena else [])
    egos = EgoBook(set(spec.ego.ids) | set(arena.ids if arena else ()), road, goal=spec.ego.goal, goals=spec.ego.goals,
                   goal_tolerance_m=spec.ego.goal_tolerance_m, cruise_speed_mps=spec.ego.cruise_speed_mps,
                   uses_goals=type(controller).needs.goals, follow_routes=arena is None,
                   drives=type(controller).needs.drives)
    ssm = SsmParams() if arena is None and spec.ego.ids else None  # lanes to measure on: not in an arena
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-run-") as tmp:  # SUMO's SSM file; gone afterwards
        ssm_file = pathlib.Path(tmp) / "ssm.xml"
        args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                         spec.sim.lateral_resolution_m, log_file, sumo_collisions=spec.sim.sumo_collisions and arena is None,
                         ssm=SsmRequest(tuple(spec.ego.ids), ssm_file, ssm) if ssm else None)
        t_loop = time.perf_counter()
        try:
            sim = SumoSim(args)
        except SumoStartError as e:
            raise sumo_load_error(scn, str(e), at_start=True) from None
        with sim:
            stack = assemble(scn, context(scn, sim.step_s, road, walls, obstacles), controller)
            for hook in hooks:
                hook.setup(sim)
            try:
                steps = rollout(sim, stack, egos, recorder, int(round(spec.sim.duration_s / sim.step_s)),
                                ([Progress(spec.sim.duration_s)] if progress else []) + list(callbacks))
            except FieldError as e:  # a goal edge not on the route SUMO gave the ego
                raise ScenarioError(str(scn.path), e.key, e.expected, e.got, show_got=e.show_got) from None
            except SumoStepError as e:  # input SUMO rejects only when it gets to it
                raise sumo_load_error(scn, str(e)) from None
            sim_time = sim.time_s
            if egos.never_departed():
                raise never_departed_error(scn, egos.never_departed(), sim_time, sim.waiting())
        t_end = time.perf_counter()
        tables = dict(stack.tables())
        if ssm:  # the file is complete once SUMO has closed
            tables["ssm_conflicts"] = read_conflicts(ssm_file)
    return RunResult(scn, Scene(road, walls, obstacles), recorder.table(), recorder.sumo_events(), egos.goals,
                     steps, sim_time, stack.stats(),
                     {"setup_s": t_loop - t_start, "loop_s": t_end - t_loop, "total_s": t_end - t_start},
                     tables, egos.tasks, recorder.signals(), ssm=ssm, persons=recorder.persons(),
                     classes=recorder.classes(), arrivals=egos.arrivals)
