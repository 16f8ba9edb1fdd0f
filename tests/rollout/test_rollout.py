"""The rollout loop: with a fake simulator (no libsumo) for its bookkeeping, and a toy controller and
toy layer registered from this test module (no change to the package) driven on real SUMO."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from sumo_avoid.actuation.kinematic import KinematicActuator
from sumo_avoid.actuation.params import ActuatorConfig
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import Keys, Needs
from sumo_avoid.rollout.assemble import Stack
from sumo_avoid.rollout.egos import EgoBook
from sumo_avoid.rollout.loop import rollout
from sumo_avoid.rollout.recorder import Recorder
from sumo_avoid.safety import LAYERS
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


class HalfSpeedLayer:
    """Halves every command (and counts)."""

    needs_scans = False
    stats_keys = Keys(("half_calls",))

    def __init__(self, params=None, ctx=None, *, enforce=True):
        self.calls = 0

    def add_ego(self, task):
        pass

    def remove_ego(self, vid):
        pass

    def stats(self):
        return {"half_calls": self.calls}

    def filter(self, obs, command):
        self.calls += 1
        return 0.5 * command


# ---------------------------------------------------------------- fake simulator
class FakeSim:
    """One straight road along +x; ego 'e' departs at step 1, a parked car 'p' stays at x = 500."""

    def __init__(self, dt=0.5):
        self.dt, self.t, self.state, self.departed_now, self.released = dt, 0.0, {}, (), []
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

    def take_over(self, vid):
        return type("Info", (), {"route_edges": ("r",), "lane_index": 0, "width_m": 1.8, "length_m": 5.0})()

    def follow_route(self, task):
        pass

    def read(self):
        ids = tuple(self.state)
        pos = np.array([self.state[v][0] for v in ids])
        hd = np.array([self.state[v][1] for v in ids])
        sp = np.array([self.state[v][2] for v in ids])
        vel = np.column_stack([sp * np.cos(hd), sp * np.sin(hd)])
        return Snapshot(self.t, ids, pos, vel, hd, np.full(len(ids), 4.0), np.full(len(ids), 1.8),
                        [v == "e" for v in ids])

    def apply(self, ids, pos, heading, speed):
        for k, v in enumerate(ids):
            self.state[v] = (np.asarray(pos[k], float), float(heading[k]), float(speed[k]))

    def release(self, vid):
        self.released.append(vid)
        self.state.pop(vid)


class StraightRoad:
    def route(self, edges, depart_lane=None):
        return np.array([[0.0, 0.0], [100.0, 0.0]]), (), np.zeros((0, 2)), ()


def test_loop_takes_over_drives_and_retires_at_the_goal_with_a_fake_simulator():
    sim = FakeSim()
    ctl = ToyController(ToyParams(speed_mps=10.0))
    layer = HalfSpeedLayer()
    stack = Stack(TruthSensor(), ctl, (layer,), KinematicActuator(ActuatorConfig(max_accel_mps2=100.0), sim.dt))
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


def test_loop_stops_at_n_steps_without_egos():
    sim = FakeSim()
    stack = Stack(TruthSensor(), ToyController(ToyParams()), (), KinematicActuator(ActuatorConfig(), sim.dt))
    egos = EgoBook({"nobody"}, StraightRoad(), goal_tolerance_m=5.0, cruise_speed_mps=10.0)
    assert rollout(sim, stack, egos, Recorder(), n_steps=7) == 7


# ---------------------------------------------------------------- real SUMO
@pytest.fixture
def toy_registered():
    CONTROLLERS.register("toy", ToyController, ToyParams)
    LAYERS.register("half_speed", HalfSpeedLayer)
    yield
    CONTROLLERS.unregister("toy")
    LAYERS.unregister("half_speed")


@pytest.mark.sumo
def test_a_toy_controller_and_layer_from_a_test_module_run_on_real_sumo(toy_registered):
    from sumo_avoid.runs.outputs import run_metrics
    from sumo_avoid.runs import runner
    from sumo_avoid.rollout.assemble import metric_keys
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(SCENARIOS / "overtaking.toml", ["sim.duration_s=20", "ego.safety=\"half_speed\"",
                                                        "controllers.toy.speed_mps=12.0"], controller="toy")
    res = runner.run(scn)
    m = run_metrics(res)
    ego = res.traj[res.traj["is_ego"]]
    assert m["controller"] == "toy" and m["toy_steps"] == m["half_calls"] > 150
    assert set(m) == metric_keys(scn).names  # the user's plug-ins declare their counters like the package's
    # the layer halves 12 m/s: the ego settles at 6 m/s along the road
    assert ego["speed"].iloc[-20:].mean() == pytest.approx(6.0, abs=0.05)
    assert math.isclose(m["collisions"], 0)


def test_the_example_controller_in_the_docs_runs_through_the_loop():
    import pathlib
    import re

    doc = (pathlib.Path(__file__).resolve().parents[2] / "docs" / "writing_a_controller.md").read_text()
    code = re.findall(r"```python\n(.*?)```", doc, re.S)[0]
    ns: dict = {}
    exec(compile(code, "writing_a_controller.md", "exec"), ns)
    ctl = ns["StraightController"](ns["StraightParams"](speed_mps=10.0))
    sim = FakeSim()
    stack = Stack(TruthSensor(), ctl, (), KinematicActuator(ActuatorConfig(max_accel_mps2=100.0), sim.dt))
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
    from sumo_avoid.rollout.assemble import metric_names
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(SCENARIOS / "crash_straight.toml", ['output.metrics=["run", "flocking"]'])
    assert metric_names(scn) == ("run", "collisions", "min_gap", "phi_coll", "phi_wall", "plugin_stats", "motion", "rules",
                                 "road_use", "comfort", "ssm", "ttc2d", "flocking")
    m = run_metrics(runner.run(scn))
    assert {"goal_reached", "collisions", "min_gap_m", "mu", "v_vel", "wrong_way_m", "min_ttc_s", "min_ttc2d_s"} <= set(m)
