"""The rollout loop: snapshot -> sensor -> controller -> actuator -> SUMO, recorded every step.

``run(scenario)`` returns a :class:`RunResult`; metrics are computed from the recorded table
afterwards (:mod:`sumo_avoid.outputs`) and never feed back into the run.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from sumo_avoid.actuation.kinematic import Motion, actuate
from sumo_avoid.rollout.arena import relaxation_step
from sumo_avoid.control import make_controller
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.core.noise import velocity_kick
from sumo_avoid.rollout.recorder import Recorder
from sumo_avoid.sumo.road import Road
from sumo_avoid.safety.danger_time import DangerTimeLayer
from sumo_avoid.scenario.spec import Scenario
from sumo_avoid.sensing.radar import Radar
from sumo_avoid.sumo.sim import SumoSim, sumo_args


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
    walls: np.ndarray | None = None  # (k,2) arena square when the scenario has an [arena], else None
    obstacles: tuple = ()  # static obstacle polygons, each (k,2) m
    radar_log: list = field(default_factory=list)  # radar scans (sensors.radar.Detections) if radar.log_detections


def _progress(done: float, total: float, t0: float) -> None:
    frac = min(done / total, 1.0)
    bar = "#" * int(30 * frac)
    print(f"\r  [{bar:<30}] {100 * frac:5.1f}%  sim {done:6.1f}/{total:.0f} s  wall {time.perf_counter() - t0:5.1f} s",
          end="", flush=True)


def _with_velocities(snap, vel_state: dict):
    """The snapshot with the egos' velocities replaced by the ones the relaxation actuator holds."""
    vel = np.array(snap.vel)
    known = [(snap.index[v], w) for v, w in vel_state.items() if v in snap.index]
    if known:
        rows, w = zip(*known)
        vel[list(rows)] = np.array(w)
    return replace(snap, vel=vel)


def route_segments(paths):
    """The egos' route paths as padded segment arrays for :func:`route_directions`: (rows with a
    path, segment starts (P, S, 2), segment vectors (P, S, 2), squared lengths (P, S)); NaN pads."""
    ok = [k for k, p in enumerate(paths) if p is not None and len(p) > 1]
    S = max([len(paths[k]) - 1 for k in ok], default=0)
    a = np.full((len(ok), S, 2), np.nan)
    b = np.full((len(ok), S, 2), np.nan)
    for i, k in enumerate(ok):
        p = np.asarray(paths[k], float)
        a[i, :len(p) - 1], b[i, :len(p) - 1] = p[:-1], p[1:]
    ab = b - a
    return ok, a, ab, (ab**2).sum(-1)


def route_directions(paths, pos, heading, segments=None) -> np.ndarray:
    """(E,) rad: direction of the segment of each ego's route path nearest to it (its heading if it
    has no path). Vectorised over egos: paths padded to one (E, S) segment array, which a caller
    may pass in precomputed (``segments = route_segments(paths)``) while the egos stay the same."""
    out = np.asarray(heading, float).copy()
    ok, a, ab, L2 = route_segments(paths) if segments is None else segments
    if not ok:
        return out
    rel = np.asarray(pos, float)[ok][:, None, :] - a
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip((rel * ab).sum(-1) / L2, 0.0, 1.0)
    d2 = ((rel - t[..., None] * ab) ** 2).sum(-1)
    d2 = np.where(np.isfinite(d2) & (L2 > 1e-18), d2, np.inf)
    seg = np.take_along_axis(ab, d2.argmin(axis=1)[:, None, None], axis=1)[:, 0]
    out[ok] = np.arctan2(seg[:, 1], seg[:, 0])
    return out


def run(scn: Scenario, *, log_file=None, progress: bool = False) -> RunResult:
    spec = scn.spec
    t_start = time.perf_counter()
    road = Road.from_net_file(scn.net_file)
    rng = np.random.default_rng(spec.sim.seed)
    controller = make_controller(spec.ego.controller, scn.params, road, rng)
    recorder = Recorder(spec.output.record_radius_m)
    # radar (own random stream) when controllers use it or the danger-time layer needs it; the layer
    # also runs as a monitor (counters only, velocities untouched) with sensor = "radar", safety = "none"
    radar = rear = layer = None
    if spec.ego.sensor == "radar" or spec.ego.safety == "danger_time":
        radar = Radar(spec.radar, np.random.default_rng([spec.sim.seed, 4]))
        layer = DangerTimeLayer(spec.safety)
        if spec.radar.rear and spec.ego.sensor == "radar":
            rear = Radar(spec.radar, np.random.default_rng([spec.sim.seed, 5]), mount="rear")
    arena = spec.arena
    ego_ids = set(spec.ego.ids) | (set(arena.ids) if arena is not None else set())
    obstacles = tuple(np.asarray(o.shape, float) for o in spec.obstacles)
    uses_goals = getattr(controller, "uses_goals", True)
    relax_mode = spec.actuator.mode == "relaxation"
    paths: dict[str, np.ndarray] = {}  # ego id -> route reference path (traffic direction with radar)
    seg_key, segs = None, None  # route_segments() of the egos in seg_key
    outer = np.random.default_rng([spec.sim.seed, 7])  # own stream: actuation noise (sumo_avoid.core.noise)
    vel_state: dict[str, np.ndarray] = {}  # relaxation mode: ego id -> 2-D velocity, m/s
    walls = None
    goals: dict[str, tuple[float, float]] = {}
    active: dict[str, float] = {}  # ego id -> signed speed held by the actuator, m/s
    finished: set[str] = set()
    args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                     spec.sim.lateral_resolution_m, log_file,
                     sumo_collisions=spec.sim.sumo_collisions and arena is None)
    t_loop = time.perf_counter()
    step = 0
    with SumoSim(args) as sim:
        dt = sim.step_s
        for ob, shape in zip(spec.obstacles, obstacles):
            sim.add_polygon(ob.id, shape)
        if arena is not None:
            from sumo_avoid.rollout.arena import random_positions, square

            walls = square(arena.origin, arena.size_m)
            if hasattr(controller, "set_walls"):
                controller.set_walls(walls)
            spawn = np.random.default_rng([spec.sim.seed, 1])  # own stream: the controller's stays put
            start = random_positions(spawn, arena.n_agents, walls, obstacles, min_spacing_m=arena.min_spacing_m,
                                     margin_m=arena.margin_m)
            heading0 = spawn.uniform(-np.pi, np.pi, arena.n_agents)
            sim.add_free_vehicles(arena.ids, start, heading0, arena.initial_speed_mps, arena.length_m, arena.width_m)
        new = [v for v in sim.departed() if v in ego_ids]
        n_steps = int(round(spec.sim.duration_s / dt))
        for step in range(n_steps + 1):
            for vid in new:  # take over egos that just entered the network
                info = sim.take_over(vid)
                path = road.route_path(list(info.route_edges), depart_lane=info.lane_index)
                goal = np.asarray(spec.ego.goal if spec.ego.goal is not None else path[-1], float)
                if uses_goals:
                    goals[vid] = (float(goal[0]), float(goal[1]))
                controller.add_ego(EgoTask(vid, goal, path, spec.ego.cruise_speed_mps))
                paths[vid] = path
                active[vid] = np.nan
            snap = sim.read()
            if vel_state:  # SUMO's reported speed of an off-lane vehicle is unreliable: use the actuator's
                snap = _with_velocities(snap, vel_state)
            recorder.record(step, snap)
            present = [v for v in active if v in snap.index]
            for vid in [v for v in active if v not in snap.index]:  # left the network on its own
                active.pop(vid)
                controller.remove_ego(vid)
                finished.add(vid)
            done = []
            if uses_goals and present:  # centre within the goal tolerance: one array operation for all egos
                gap = snap.pos[[snap.index[v] for v in present]] - np.array([goals[v] for v in present])
                done = [v for v, d in zip(present, np.hypot(gap[:, 0], gap[:, 1])) if d <= spec.ego.goal_tolerance_m]
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
                det = radar.scan(snap, present, obstacles) if radar is not None else None
                seen = along = None
                if spec.ego.sensor == "radar":  # with a rear radar: one fused memory (sensors.tracker)
                    if seg_key != present:  # the padded route segments only change with the egos
                        seg_key, segs = list(present), route_segments([paths.get(v) for v in present])
                    along = route_directions(None, snap.pos[rows], snap.heading[rows], segs)
                    seen = (radar.objects(det, along) if rear is None
                            else radar.objects((det, rear.scan(snap, present, obstacles)), along))
                    seen = seen if isinstance(seen, tuple) else (seen,)
                v_des = controller.act(Observation(snap, tuple(present), obstacles, seen, along))
                if layer is not None:
                    v_lim, _ = layer.apply(v_des, det, snap.width[rows], speed, dt)
                    v_des = v_lim if spec.ego.safety == "danger_time" else v_des
                if relax_mode:
                    vel0 = np.array([vel_state[v] if v in vel_state else snap.vel[snap.index[v]] for v in present])
                    kick = (velocity_kick(outer, spec.actuator.outer_noise_m2ps3, dt, len(present))
                            if spec.actuator.outer_noise_m2ps3 > 0 else None)
                    pos1, vel1, head1, speed1 = relaxation_step(snap.pos[rows], vel0, snap.heading[rows], v_des,
                                                                spec.actuator.tau_s,
                                                                spec.actuator.relax_max_accel_mps2, dt, kick)
                    vel_state.update(zip(present, vel1))
                    motion = Motion(pos1, head1, speed1)
                else:
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
    stats = {**controller.stats(), **(layer.stats() if layer is not None else {})}
    return RunResult(scn, recorder.table(), recorder.sumo_events(), goals, road, step, sim_time,
                     stats, {"setup_s": t_loop - t_start, "loop_s": t_end - t_loop,
                             "total_s": t_end - t_start}, walls, obstacles,
                     (radar.log if radar is not None else []) + (rear.log if rear is not None else []))
