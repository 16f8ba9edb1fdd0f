"""One scenario, one run: start SUMO, set the scene up, assemble the plug-ins, roll out, record.

``run(scenario)`` returns a :class:`~sumo_avoid.rollout.result.RunResult`; metrics are computed
from its recording afterwards (:mod:`sumo_avoid.metrics`) and never feed back into the run.
"""
from __future__ import annotations

import contextlib
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


def named(scn, err: ScenarioError) -> ScenarioError:
    """``err`` naming the SUMO configuration's option (or ``--ego``) when the value came from one."""
    return scn.sumocfg.rename(err) if scn.sumocfg else err


def load_error(scn, message: str, at_start: bool = False) -> ScenarioError:
    """SUMO's refusal of the scenario's files (:func:`sumo_load_error`), named as :func:`named` does."""
    return named(scn, sumo_load_error(scn, message, at_start))


@contextlib.contextmanager
def scenario_errors(scn):
    """Input found bad only once SUMO runs, as one :class:`ScenarioError` naming the scenario file
    and key: a goal edge not on the route SUMO gave an ego, an element SUMO rejects when it gets to it."""
    try:
        yield
    except FieldError as e:
        raise ScenarioError(str(scn.path), e.key, e.expected, e.got, show_got=e.show_got) from None
    except SumoStepError as e:
        raise load_error(scn, str(e)) from None


class OpenRun:
    """One run opened to be stepped: SUMO started (``sim``), the scene set up, the plug-ins assembled
    (``stack``), the egos' book (``egos``) and the ``recorder``; :meth:`result` closes SUMO and
    returns the :class:`RunResult`. A context manager (SUMO and its SSM file's folder end on exit).
    :func:`run` rolls it out to the end; the Gymnasium environment steps it with the loop's halves.
    ``make_controller(ctx)`` builds the controller instead of ``ego.controller``'s registry entry."""

    def __init__(self, scn, *, log_file=None, make_controller=None):
        spec = self.spec = scn.spec
        self.scn = scn
        self.t_start = time.perf_counter()
        arena = spec.arena
        road = Road.from_net_file(scn.net_file)
        walls = square(arena.origin, arena.size_m) if arena is not None else None
        obstacles = tuple(o.polygon for o in spec.obstacles)
        self.scene = Scene(road, walls, obstacles)
        ctx = context(scn, spec.sim.step_s, road, walls, obstacles)  # steering limits and tables: assemble.context
        with scenario_errors(scn):  # a controller's parameter found bad when it is built (a policy that does not import)
            self.controller = controller_for(scn, ctx) if make_controller is None else make_controller(ctx)
        self.recorder = Recorder(spec.output.record_radius_m)
        self.hooks = [StaticObstacles(spec.obstacles, obstacles)] + ([ArenaSpawn(arena, walls, obstacles, ctx.rng(1))] if arena else [])
        self.egos = EgoBook(set(spec.ego.ids) | set(arena.ids if arena else ()), road, goal=spec.ego.goal, goals=spec.ego.goals,
                            goal_tolerance_m=spec.ego.goal_tolerance_m, cruise_speed_mps=spec.ego.cruise_speed_mps,
                            uses_goals=type(self.controller).needs.goals, follow_routes=arena is None,
                            drives=type(self.controller).needs.drives, turn_radius_m=ctx.turn_radius_m)
        self.ssm = SsmParams() if arena is None and spec.ego.ids else None  # lanes to measure on: not in an arena
        self.log_file = log_file
        self._tmp = None
        self.sim = None

    def __enter__(self) -> OpenRun:
        spec, scn, scene = self.spec, self.scn, self.scene
        self._tmp = tempfile.TemporaryDirectory(prefix="sumo-avoid-run-")  # SUMO's SSM file; gone afterwards
        self.ssm_file = pathlib.Path(self._tmp.name) / "ssm.xml"
        args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, spec.sim.step_s, spec.sim.seed,
                         spec.sim.lateral_resolution_m, self.log_file,
                         sumo_collisions=spec.sim.sumo_collisions and spec.arena is None,
                         ssm=SsmRequest(tuple(spec.ego.ids), self.ssm_file, self.ssm) if self.ssm else None,
                         begin_s=spec.sim.begin_s, options=scn.sumo_options)
        self.t_loop = time.perf_counter()
        try:
            self.sim = SumoSim(args)
        except SumoStartError as e:
            self._tmp.cleanup()
            raise load_error(scn, str(e), at_start=True) from None
        self.sim.apart = scene.road.apart if spec.arena is None else {}  # two levels whatever the heights (road.grade)
        self.sim.world_before_egos = spec.output.record_radius_m <= 0  # recorded only near egos: none before them
        try:
            for note in scn.sumocfg.notes if scn.sumocfg else ():
                self.sim.note(note)
            self.stack = assemble(scn, context(scn, self.sim.step_s, scene.road, scene.walls, scene.obstacles),
                                  self.controller)
            for hook in self.hooks:
                hook.setup(self.sim)
        except BaseException:
            self.__exit__()
            raise
        self.n_steps = int(round(spec.sim.duration_s / self.sim.step_s))
        return self

    def __exit__(self, *exc) -> None:
        if self.sim is not None:
            self.sim.close()
        if self._tmp is not None:
            self._tmp.cleanup()

    def result(self, steps: int) -> RunResult:
        """Close SUMO and return the run's recording; raises :class:`ScenarioError` for an ego that never
        departed."""
        sim, egos, recorder = self.sim, self.egos, self.recorder
        sim_time = sim.time_s
        if egos.never_departed():
            raise named(self.scn, never_departed_error(self.scn, egos.never_departed(), sim_time, sim.waiting()))
        sim.close()
        t_end = time.perf_counter()
        tables = dict(self.stack.tables())
        if self.ssm:  # the file is complete once SUMO has closed
            tables["ssm_conflicts"] = read_conflicts(self.ssm_file)
        return RunResult(self.scn, self.scene, recorder.table(), recorder.sumo_events(), egos.goals,
                         steps, sim_time, self.stack.stats(),
                         {"setup_s": self.t_loop - self.t_start, "loop_s": t_end - self.t_loop, "total_s": t_end - self.t_start},
                         tables, egos.tasks, recorder.signals(), ssm=self.ssm, persons=recorder.persons(),
                         classes=recorder.classes(), arrivals=self.egos.arrivals, detours=dict(egos.detours))


def run(scn, *, log_file=None, progress: bool = False, callbacks=()) -> RunResult:
    """Run one scenario. Raises :class:`ScenarioError` (one line, naming the scenario file and key)
    for input found bad only once SUMO runs: files SUMO cannot load (at the start or when it gets to
    an element, e.g. an invalid departLane), a goal edge not on an ego's route, an ego that never departed.
    ``callbacks``: more rollout callbacks (``on_step``, ``on_end``) beside the progress bar."""
    with OpenRun(scn, log_file=log_file) as r:
        with scenario_errors(scn):
            steps = rollout(r.sim, r.stack, r.egos, r.recorder, r.n_steps,
                            ([Progress(scn.spec.sim.duration_s)] if progress else []) + list(callbacks))
        return r.result(steps)
