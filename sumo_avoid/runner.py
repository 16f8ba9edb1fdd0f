"""The rollout loop: snapshot -> sensor -> controller -> actuator -> SUMO, recorded every step.

``run(scenario)`` returns a :class:`RunResult`; metrics are computed from the recorded table
afterwards (:mod:`sumo_avoid.evaluate`) and never feed back into the run.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .actuator import actuate
from .controllers import make_controller
from .controllers.base import EgoTask, Observation
from .recorder import Recorder
from .road import Road
from .scenario import Scenario
from .sim import SumoSim, sumo_args


@dataclass
class RunResult:
    scenario: Scenario
    traj: pd.DataFrame
    sumo_events: pd.DataFrame
    goals: dict  # ego id -> (x, y)
    road: Road
    steps: int
    sim_time_s: float
    controller_stats: dict
    timings: dict = field(default_factory=dict)


def _progress(done: float, total: float, t0: float) -> None:
    frac = min(done / total, 1.0)
    bar = "#" * int(30 * frac)
    print(f"\r  [{bar:<30}] {100 * frac:5.1f}%  sim {done:6.1f}/{total:.0f} s  wall {time.perf_counter() - t0:5.1f} s",
          end="", flush=True)


def run(scn: Scenario, *, log_file=None, progress: bool = False) -> RunResult:
    spec = scn.spec
    t_start = time.perf_counter()
    road = Road.from_net_file(scn.net_file)
    rng = np.random.default_rng(spec.sim.seed)
    controller = make_controller(spec.ego.controller, scn.params, road, rng)
    recorder = Recorder(spec.output.record_radius_m)
    ego_ids = set(spec.ego.ids)
    goals: dict[str, tuple[float, float]] = {}
    active: dict[str, float] = {}  # ego id -> signed speed held by the actuator, m/s
    finished: set[str] = set()
    args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                     spec.sim.lateral_resolution_m, log_file)
    t_loop = time.perf_counter()
    step = 0
    with SumoSim(args) as sim:
        dt = sim.step_s
        new = [v for v in sim.departed() if v in ego_ids]
        n_steps = int(round(spec.sim.duration_s / dt))
        for step in range(n_steps + 1):
            for vid in new:  # take over egos that just entered the network
                info = sim.take_over(vid)
                path = road.route_path(list(info.route_edges), depart_lane=info.lane_index)
                goal = np.asarray(spec.ego.goal if spec.ego.goal is not None else path[-1], float)
                goals[vid] = (float(goal[0]), float(goal[1]))
                controller.add_ego(EgoTask(vid, goal, path, spec.ego.cruise_speed_mps))
                active[vid] = np.nan
            snap = sim.read()
            recorder.record(step, snap)
            present = [v for v in active if v in snap.index]
            for vid in [v for v in active if v not in snap.index]:  # left the network on its own
                active.pop(vid)
                controller.remove_ego(vid)
                finished.add(vid)
            done = [v for v in present
                    if np.hypot(*(snap.pos[snap.index[v]] - goals[v])) <= spec.ego.goal_tolerance_m]
            for vid in done:
                sim.release(vid)
                controller.remove_ego(vid)
                active.pop(vid)
                finished.add(vid)
            present = [v for v in present if v not in done]
            if step == n_steps or (len(finished) == len(ego_ids) and not active):
                break
            if present:
                rows = np.array([snap.index[v] for v in present])
                speed = np.array([active[v] for v in present])
                speed = np.where(np.isnan(speed), snap.speed[rows], speed)
                v_des = controller.act(Observation(snap, tuple(present)))
                motion = actuate(snap.pos[rows], snap.heading[rows], speed, v_des, spec.actuator, dt)
                sim.apply(present, motion.pos, motion.heading, motion.speed)
                for k, vid in enumerate(present):
                    active[vid] = float(motion.speed[k])
            recorder.record_sumo_collisions(step + 1, sim.step())
            new = [v for v in sim.departed() if v in ego_ids]
            if progress and step % 50 == 0:
                _progress(snap.time_s, spec.sim.duration_s, t_loop)
        sim_time = sim.time_s
    if progress:
        _progress(sim_time, spec.sim.duration_s, t_loop)
        print()
    t_end = time.perf_counter()
    return RunResult(scn, recorder.table(), recorder.sumo_events(), goals, road, step, sim_time,
                     controller.stats(), {"setup_s": t_loop - t_start, "loop_s": t_end - t_loop,
                                          "total_s": t_end - t_start})
