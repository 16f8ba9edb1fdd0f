"""One scenario, one run: start SUMO, set the scene up, assemble the plug-ins, roll out, record.

``run(scenario)`` returns a :class:`~sumo_avoid.rollout.result.RunResult`; metrics are computed
from its recording afterwards (:mod:`sumo_avoid.metrics`) and never feed back into the run.
"""
from __future__ import annotations

import pathlib
import tempfile
import time

from tqdm import tqdm

from sumo_avoid.core.interfaces import Context
from sumo_avoid.rollout.arena import ArenaSpawn, StaticObstacles, square
from sumo_avoid.rollout.assemble import assemble, controller_for
from sumo_avoid.rollout.egos import EgoBook
from sumo_avoid.rollout.loop import rollout
from sumo_avoid.rollout.recorder import Recorder
from sumo_avoid.rollout.result import RunResult, Scene
from sumo_avoid.sumo.road import Road
from sumo_avoid.sumo.sim import SumoSim, sumo_args
from sumo_avoid.sumo.ssm import SsmParams, SsmRequest, read_conflicts


class Progress:
    """A tqdm bar over simulated seconds (the loop's callback)."""

    def __init__(self, duration_s: float):
        self.bar = tqdm(total=round(duration_s, 3), unit="s sim", leave=True, dynamic_ncols=True,
                        bar_format="  {l_bar}{bar}| {n:.0f}/{total:.0f} s sim [{elapsed}<{remaining}]")

    def on_step(self, snap, n_steps: int) -> None:
        self.bar.update(max(0.0, min(snap.time_s, self.bar.total) - self.bar.n))

    def on_end(self) -> None:
        self.bar.close()


def run(scn, *, log_file=None, progress: bool = False) -> RunResult:
    spec = scn.spec
    t_start = time.perf_counter()
    arena = spec.arena
    road = Road.from_net_file(scn.net_file)
    walls = square(arena.origin, arena.size_m) if arena is not None else None
    obstacles = tuple(o.polygon for o in spec.obstacles)
    ctx = Context(spec.sim.seed, spec.sim.step_s, road, walls, obstacles)
    controller = controller_for(scn, ctx)
    recorder = Recorder(spec.output.record_radius_m)
    hooks = [StaticObstacles(spec.obstacles, obstacles)] + ([ArenaSpawn(arena, walls, obstacles, ctx.rng(1))] if arena else [])
    egos = EgoBook(set(spec.ego.ids) | set(arena.ids if arena else ()), road, goal=spec.ego.goal,
                   goal_tolerance_m=spec.ego.goal_tolerance_m, cruise_speed_mps=spec.ego.cruise_speed_mps,
                   uses_goals=type(controller).needs.goals)
    ssm = SsmParams() if arena is None and spec.ego.ids else None  # lanes to measure on: not in an arena
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-run-") as tmp:  # SUMO's SSM file; gone afterwards
        ssm_file = pathlib.Path(tmp) / "ssm.xml"
        args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                         spec.sim.lateral_resolution_m, log_file, sumo_collisions=spec.sim.sumo_collisions and arena is None,
                         ssm=SsmRequest(tuple(spec.ego.ids), ssm_file, ssm) if ssm else None)
        t_loop = time.perf_counter()
        with SumoSim(args) as sim:
            stack = assemble(scn, Context(spec.sim.seed, sim.step_s, road, walls, obstacles), controller)
            for hook in hooks:
                hook.setup(sim)
            steps = rollout(sim, stack, egos, recorder, int(round(spec.sim.duration_s / sim.step_s)),
                            [Progress(spec.sim.duration_s)] if progress else [])
            sim_time = sim.time_s
        t_end = time.perf_counter()
        tables = dict(stack.tables())
        if ssm:  # the file is complete once SUMO has closed
            tables["ssm_conflicts"] = read_conflicts(ssm_file)
    return RunResult(scn, Scene(road, walls, obstacles), recorder.table(), recorder.sumo_events(), egos.goals,
                     steps, sim_time, stack.stats(),
                     {"setup_s": t_loop - t_start, "loop_s": t_end - t_loop, "total_s": t_end - t_start},
                     tables, egos.tasks, recorder.signals(), ssm=ssm)
