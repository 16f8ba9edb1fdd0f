"""The rollout loop: with a fake simulator (no libsumo) for its bookkeeping, and a toy controller, a
toy layer with its own ``[layers.NAME]`` table and a toy sensor with its own ``[sensors.NAME]`` table,
registered from this test module (no change to the package), driven on real SUMO."""
from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import numpy as np
import pytest

from sumo_avoid.actuation.kinematic import KinematicActuator, KinematicParams
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.interfaces import Context
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import Keys, Needs, Observation
from sumo_avoid.rollout.assemble import Stack
from sumo_avoid.rollout.egos import EgoBook
from sumo_avoid.rollout.loop import rollout
from sumo_avoid.rollout.recorder import Recorder
from sumo_avoid.safety import LAYERS
from sumo_avoid.sensing import SENSORS
from sumo_avoid.sensing.sensors import TruthSensor
from tests.conftest import SCENARIOS


# ---------------------------------------------------------------- toy plug-ins (user code)
@dataclass(frozen=True)
class ToyParams:
    speed_mps: float = field_doc(5.0, doc="speed along the route, m/s")


class ToyController:
    """Drives along the first segment direction of its route at a fixed speed."""

    needs = Needs(goals=True)
    metrics = ()
    stats_keys = Keys(("toy_steps",))

    def __init__(self, params: ToyParams, ctx=None):
        self.p = params
        self.dirs: dict[str, np.ndarray] = {}
        self.seen: list[tuple[str, ...]] = []

    def add_ego(self, task):
        d = task.path[-1] - task.path[0]
        self.dirs[task.vid] = d / np.hypot(*d)

    def remove_ego(self, vid):
        self.dirs.pop(vid)

    def stats(self):
        return {"toy_steps": len(self.seen)}

    def tables(self):
        return {}

    def act(self, obs):
        self.seen.append(obs.ego_ids)
        return np.array([self.p.speed_mps * self.dirs[v] for v in obs.ego_ids]).reshape(-1, 2)


@dataclass(frozen=True)
class ScaleParams:
    factor: float = field_doc(1.0, doc="every command is multiplied by this")


class ScaleLayer:
    """Scales every command by its table's ``factor`` (and counts)."""

    needs_scans = False
    monitor_when_scans = False
    stats_keys = Keys(("scale_calls",))

    def __init__(self, params: ScaleParams = ScaleParams(0.5), ctx=None, *, enforce=True):
        self.p = params
        self.calls = 0

    def add_ego(self, task):
        pass

    def remove_ego(self, vid):
        pass

    def stats(self):
        return {"scale_calls": self.calls}

    def filter(self, obs, command):
        self.calls += 1
        return self.p.factor * command


@dataclass(frozen=True)
class GapLogParams:
    every_steps: int = field_doc(1, positive=True, doc="log each ego's nearest other vehicle every this many steps")


class GapLogSensor:
    """Ground truth for the controller; logs each ego's distance to the nearest other vehicle's centre
    every ``every_steps`` steps (its table ``gap_log``)."""

    provides_scans = False

    def __init__(self, params: GapLogParams, ctx, *, needs_scans=False, v2v=None):
        self.p, self.steps, self.rows = params, 0, []

    def add_ego(self, task):
        pass

    def remove_ego(self, vid):
        pass

    def stats(self):
        return {}

    def tables(self):
        import pandas as pd

        return {"gap_log": pd.DataFrame(self.rows, columns=["time_s", "ego", "nearest_m"])}

    def observe(self, snap, ego_ids, ego_speed):
        rows = np.array([snap.index[v] for v in ego_ids], dtype=int)
        if self.steps % self.p.every_steps == 0:
            for vid, r in zip(ego_ids, rows):
                d = np.hypot(*(snap.pos - snap.pos[r]).T)
                d[r] = np.inf
                self.rows.append((snap.time_s, vid, float(d.min())))
        self.steps += 1
        return Observation(snap, tuple(ego_ids), rows, ego_speed)


# ---------------------------------------------------------------- fake simulator
class FakeSim:
    """One straight road along +x; ego 'e' departs at step 1, a parked car 'p' stays at x = 500."""

    def __init__(self, dt=0.5):
        self.dt, self.t, self.state, self.departed_now, self.released = dt, 0.0, {}, (), []
        self.taken, self.applied = [], 0
        self.state["p"] = (np.array([500.0, 0.0]), 0.0, 0.0)

    def departed(self):
        return self.departed_now

    def step(self):
        self.t += self.dt
        self.departed_now = ()
        if abs(self.t - self.dt) < 1e-9:
            self.state["e"] = (np.array([0.0, 0.0]), 0.0, 0.0)
            self.departed_now = ("e",)
        return []

    def take_over(self, vid, drive=True):
        self.taken.append((vid, drive))
        return type("Info", (), {"route_edges": ("r",), "lane_index": 0, "width_m": 1.8, "length_m": 5.0,
                                 "vclass": "passenger"})()

    def follow_route(self, task):
        pass

    def arrived(self):
        return frozenset()

    def read(self):
        ids = tuple(self.state)
        pos = np.array([self.state[v][0] for v in ids])
        hd = np.array([self.state[v][1] for v in ids])
        sp = np.array([self.state[v][2] for v in ids])
        vel = np.column_stack([sp * np.cos(hd), sp * np.sin(hd)])
        return Snapshot(self.t, ids, pos, vel, hd, np.full(len(ids), 4.0), np.full(len(ids), 1.8),
                        [v == "e" for v in ids])

    def apply(self, ids, pos, heading, speed):
        self.applied += 1
        for k, v in enumerate(ids):
            self.state[v] = (np.asarray(pos[k], float), float(heading[k]), float(speed[k]))

    def release(self, vid):
        self.released.append(vid)
        self.state.pop(vid)


class StraightRoad:
    def route(self, edges, depart_lane=None, vclass=None):
        return np.array([[0.0, 0.0], [100.0, 0.0]]), (), np.zeros((0, 2)), ()


def test_loop_takes_over_drives_and_retires_at_the_goal_with_a_fake_simulator():
    sim = FakeSim()
    ctl = ToyController(ToyParams(speed_mps=10.0))
    layer = ScaleLayer()
    stack = Stack(TruthSensor(), ctl, (layer,), KinematicActuator(KinematicParams(max_accel_mps2=100.0), Context(1, sim.dt)))
    egos = EgoBook({"e"}, StraightRoad(), goal_tolerance_m=5.0, cruise_speed_mps=10.0)
    rec = Recorder()
    last = rollout(sim, stack, egos, rec, n_steps=1000)
    # departs at t = 0.5; the layer halves 10 m/s to 5 m/s, reached within one step (accel limit 100):
    # x = 2.5 m per step, within 5 m of x = 100 after 38 steps of driving (steps 1-38); step 39
    # reads x = 95, retires the ego and ends the run
    assert egos.finished == {"e"} and sim.released == ["e"]
    assert last == 1 + 38
    assert layer.calls == 38 and len(ctl.seen) == 38 and ctl.seen[0] == ("e",)
    assert egos.goals == {"e": (100.0, 0.0)}
    t = rec.table()
    assert set(t["id"]) == {"e", "p"}
    assert t.loc[t["id"] == "e", "x"].max() == pytest.approx(95.0)


def test_an_ego_left_to_sumo_is_taken_over_without_driving_and_never_sensed_controlled_or_moved():
    """Needs(drives=False) (controller "sumo"): the ego is an ego (taken over with drive=False, a goal,
    recorded, retired there) but the loop hands nobody to the sensor, controller, layers or actuator."""
    sim = FakeSim()
    ctl = ToyController(ToyParams(speed_mps=10.0))
    layer = ScaleLayer()
    stack = Stack(TruthSensor(), ctl, (layer,), KinematicActuator(KinematicParams(), Context(1, sim.dt)))
    egos = EgoBook({"e"}, StraightRoad(), goal_tolerance_m=5.0, cruise_speed_mps=10.0, drives=False)
    rec = Recorder()
    assert rollout(sim, stack, egos, rec, n_steps=20) == 20
    assert sim.taken == [("e", False)] and sim.applied == 0
    assert ctl.seen == [] and layer.calls == 0 and egos.goals == {"e": (100.0, 0.0)}
    t = rec.table()
    assert t.loc[t["id"] == "e", "is_ego"].all() and (t.loc[t["id"] == "e", "x"] == 0.0).all()
    assert egos.arrivals == {} and not egos.finished


class ArrivingSim(FakeSim):
    """SUMO takes ego 'e' out at the end of its route at t = 3 s (last recorded at 2.5 s)."""

    def __init__(self):
        super().__init__()
        self.gone = frozenset()

    def step(self):
        out = super().step()
        self.gone = frozenset()
        if abs(self.t - 3.0) < 1e-9:
            self.state.pop("e")
            self.gone = frozenset({"e"})
        return out

    def arrived(self):
        return self.gone


@pytest.mark.parametrize("drives, goal, arrivals", [(False, None, {"e": 2.5}), (False, "r", {"e": 2.5}),
                                                    (False, (50.0, 0.0), {}), (True, None, {})])
def test_an_ego_sumo_drives_to_its_route_end_reaches_a_goal_there(drives, goal, arrivals):
    """Only an ego SUMO drives, only at its route's end (no goal given, or its last edge): a point goal
    is reached at the point, and a driven ego at its goal point (the plug-in drives it there)."""
    sim = ArrivingSim()
    stack = Stack(TruthSensor(), ToyController(ToyParams(speed_mps=0.0)), (),
                  KinematicActuator(KinematicParams(), Context(1, sim.dt)))
    egos = EgoBook({"e"}, StraightRoad(), goal=goal, goal_tolerance_m=5.0, cruise_speed_mps=10.0, drives=drives)
    rollout(sim, stack, egos, Recorder(), n_steps=20)
    assert egos.arrivals == arrivals and egos.finished == {"e"}


def test_loop_stops_at_n_steps_without_egos():
    sim = FakeSim()
    stack = Stack(TruthSensor(), ToyController(ToyParams()), (), KinematicActuator(KinematicParams(), Context(1, sim.dt)))
    egos = EgoBook({"nobody"}, StraightRoad(), goal_tolerance_m=5.0, cruise_speed_mps=10.0)
    assert rollout(sim, stack, egos, Recorder(), n_steps=7) == 7


# ---------------------------------------------------------------- real SUMO
@pytest.fixture
def toy_registered():
    CONTROLLERS.register("toy", ToyController, ToyParams)
    LAYERS.register("scale", ScaleLayer, ScaleParams)
    SENSORS.register("gap_log", GapLogSensor, GapLogParams)
    yield
    CONTROLLERS.unregister("toy")
    LAYERS.unregister("scale")
    SENSORS.unregister("gap_log")


def toy_scenario(tmp_path, tables: str) -> pathlib.Path:
    """overtaking.toml (paths made absolute) with the toy sensor and the toy layer after the rules
    layer in [ego], and ``tables`` appended."""
    text = (SCENARIOS / "overtaking.toml").read_text()
    text = text.replace('"../nets/overtaking.net.xml"', f'"{(SCENARIOS.parent / "nets" / "overtaking.net.xml").as_posix()}"')
    text = text.replace('"overtaking.rou.xml"', f'"{(SCENARIOS / "overtaking.rou.xml").as_posix()}"')
    text = text.replace("[ego]\n", '[ego]\nsensor = "gap_log"\nlayers = ["traffic", "scale"]\n', 1)
    path = tmp_path / "toy.toml"
    path.write_text(text + "\n" + tables)
    return path


TOY_TABLES = "[layers.scale]\nfactor = 0.5\n\n[sensors.gap_log]\nevery_steps = 10\n\n[controllers.toy]\nspeed_mps = 12.0\n"


@pytest.mark.sumo
def test_a_toy_controller_layer_and_sensor_from_a_test_module_run_on_real_sumo(toy_registered, tmp_path):
    """Registered from here with their parameter tables, chosen and parameterised in the scenario
    file like the package's own: the toy layer scales by its [layers.scale] factor after the rules
    layer, the toy sensor logs at its [sensors.gap_log] period, their tables reach Context.params."""
    from sumo_avoid.runs import runner
    from sumo_avoid.runs.declared import metric_keys
    from sumo_avoid.runs.outputs import run_metrics
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(toy_scenario(tmp_path, TOY_TABLES), ["sim.duration_s=20"], controller="toy")
    assert scn.table("layers.scale") == ScaleParams(0.5) and scn.table("sensors.gap_log") == GapLogParams(10)
    res = runner.run(scn)
    m = run_metrics(res)
    ego = res.traj[res.traj["is_ego"]]
    assert (m["controller"], m["sensor"], m["safety"]) == ("toy", "gap_log", "scale")
    assert m["toy_steps"] == m["scale_calls"] > 150 and "rules_signal_stops" in m  # the rules layer ran too
    assert set(m) == metric_keys(scn).names  # the user's plug-ins declare their counters like the package's
    assert not any(k.startswith("radar_") for k in m)  # no scans: no danger-time monitor
    # the sensor's table: one row every 10 steps the ego was driven
    log = res.tables["gap_log"]
    assert len(log) == math.ceil(m["toy_steps"] / 10) and (log["ego"] == "ego").all() and (log["nearest_m"] > 0).all()
    # the layer scales 12 m/s by 0.5: the ego settles at 6 m/s along the road
    assert ego["speed"].iloc[-20:].mean() == pytest.approx(6.0, abs=0.05)
    assert math.isclose(m["collisions"], 0)


@pytest.mark.parametrize("tables, key", [
    ("[layers.scale]\nfactor = \"half\"\n", "layers.scale.factor"),
    ("[layers.scale]\nfactr = 0.5\n", "layers.scale.factr"),
    ("[sensors.gap_log]\nevery_steps = 0\n", "sensors.gap_log.every_steps"),
    ("[sensors.gap_logger]\nevery_steps = 2\n", "sensors.gap_logger"),
])
def test_the_toy_plug_ins_tables_are_validated_like_the_package_s(toy_registered, tmp_path, tables, key):
    from sumo_avoid.core.config import ScenarioError
    from sumo_avoid.scenario import spec as scenario

    path = toy_scenario(tmp_path, tables)
    with pytest.raises(ScenarioError) as err:
        scenario.load(path, controller="toy")
    assert str(err.value).startswith(f"{path}: key '{key}': expected ")


def test_the_example_controller_in_the_docs_runs_through_the_loop():
    import re

    doc = (pathlib.Path(__file__).resolve().parents[2] / "docs" / "writing_a_controller.md").read_text()
    code = re.findall(r"```python\n(.*?)```", doc, re.S)[0]
    ns: dict = {}
    exec(compile(code, "writing_a_controller.md", "exec"), ns)
    ctl = ns["StraightController"](ns["StraightParams"](speed_mps=10.0))
    sim = FakeSim()
    stack = Stack(TruthSensor(), ctl, (), KinematicActuator(KinematicParams(max_accel_mps2=100.0), Context(1, sim.dt)))
    egos = EgoBook({"e"}, StraightRoad(), goal_tolerance_m=5.0, cruise_speed_mps=10.0)
    rollout(sim, stack, egos, Recorder(), n_steps=1000)
    assert egos.finished == {"e"} and ctl.tasks == {} and ctl.stats() == {} and ctl.tables() == {}
    # the example is act() and its parameters: everything else comes from BaseController
    assert {k for k in vars(ns["StraightController"]) if not k.startswith("__")} == {"act"}


@pytest.mark.sumo
def test_output_metrics_adds_to_the_standard_set():
    """``output.metrics`` names metrics beside the standard ones (which the summary, plots, ledger
    and suites read): a subset removes nothing, and flocking's order parameters can be asked for a
    car controller (with [controllers.flocking]'s v_flock and r_c)."""
    from sumo_avoid.runs.outputs import run_metrics
    from sumo_avoid.runs import runner
    from sumo_avoid.runs.declared import metric_names
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(SCENARIOS / "crash_straight.toml", ['output.metrics=["run", "flocking"]'])
    assert metric_names(scn) == ("run", "collisions", "vru", "min_gap", "phi_coll", "phi_wall", "plugin_stats", "motion",
                                 "rules", "crossings", "road_use", "comfort", "ssm", "ttc2d", "flocking")
    m = run_metrics(runner.run(scn))
    assert {"goal_reached", "collisions", "min_gap_m", "mu", "v_vel", "wrong_way_m", "min_ttc_s", "min_ttc2d_s"} <= set(m)


class UturnRoad(StraightRoad):
    """A road whose route planner finds a way round the route's U-turn: ("r", "x", "y") -> ("r", "z", "y")."""

    def without_uturns(self, edges, vclass):
        return ("r", "z", "y") if tuple(edges) == ("r", "x", "y") else None

    def route(self, edges, depart_lane=None, vclass=None):  # a junction link after each edge (a goal edge's stop line)
        path, _, limits, lanes = super().route(edges, depart_lane, vclass)
        return path, tuple(type("Link", (), {"s_stop_m": 30.0 * (k + 1)})() for k in range(len(edges))), limits, lanes


class UturnSim(FakeSim):
    def __init__(self, accept: bool):
        super().__init__()
        self.accept, self.routes, self.notes = accept, [], []

    def take_over(self, vid, drive=True):
        info = super().take_over(vid, drive)
        info.route_edges = ("r", "x", "y")
        return info

    def set_route(self, vid, edges):
        self.routes.append((vid, tuple(edges)))
        return self.accept

    def note(self, text):
        self.notes.append(text)


@pytest.mark.parametrize("accept, radius, goal, drives, detour", [
    (True, 4.25, None, True, True),  # SUMO takes the route round the U-turn: the ego drives it
    (False, 4.25, None, True, False),  # SUMO refuses it: the route it was given
    (True, 0.0, None, True, False),  # no turning radius (it may turn on the spot): no detour
    (True, 4.25, [100.0, 0.0], True, False),  # a goal point may lie on the stretch the detour leaves out
    (True, 4.25, "z", True, True),  # a goal edge on the detour
    (True, 4.25, "x", True, False),  # ... and one the detour misses
    (True, 4.25, None, False, False),  # SUMO's driver turns on the spot
])
def test_an_ego_is_given_the_route_round_its_u_turn_where_it_can(accept, radius, goal, drives, detour):
    sim = UturnSim(accept)
    sim.step()
    egos = EgoBook({"e"}, UturnRoad(), goal=goal, goal_tolerance_m=5.0, cruise_speed_mps=10.0, drives=drives,
                   turn_radius_m=radius)
    egos.take_over(sim, "e")
    assert egos.detours == ({"e": (("r", "x", "y"), ("r", "z", "y"))} if detour else {})
    assert bool(sim.notes) == detour
    assert sim.routes == ([("e", ("r", "z", "y"))] if detour or (drives and radius and goal is None) else [])
