"""The traffic-rules layer on real SUMO, on a net SUMO's netgenerate builds here (a 3x3 grid, one
signalised junction B1) with a scripted signal program: red then green, or a late yellow. The ego
drives straight through B1 with the scripted controller (12 m/s east), so what is tested is the
layer alone: any controller's command is held at the line."""
import math
import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.runs import outputs
from sumo_avoid.road.polyline import polyline_project_many
from sumo_avoid.core.types import EgoTask
from sumo_avoid.runs import runner
from sumo_avoid.safety.traffic import RulesParams, road_speed_cap
from sumo_avoid.scenario import spec as scenario

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
N_LINKS = 12  # links of B1 in this net (netgenerate: 4 arms x right/straight/left, no turnarounds)


def _grid_net(d: pathlib.Path, *options: str) -> pathlib.Path:
    """A netgenerate 3x3 grid (150 m, one lane) with ``options`` and the ego's route A1B1 B1C1."""
    subprocess.run([str(BIN / "netgenerate"), "--grid", "--grid.x-number", "3", "--grid.y-number", "3",
                    "--grid.length", "150", "--default.lanenumber", "1", "--no-turnarounds", "true",
                    *options, "--seed", "1", "-o", str(d / "grid.net.xml")],
                   check=True, capture_output=True)
    (d / "ego.rou.xml").write_text(
        '<routes>\n  <vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="20"/>\n'
        '  <route id="r" edges="A1B1 B1C1"/>\n'
        '  <vehicle id="ego" type="ego_car" route="r" depart="0" departPos="5" departSpeed="12"/>\n</routes>\n')
    return d


@pytest.fixture(scope="module")
def grid(tmp_path_factory):
    return _grid_net(tmp_path_factory.mktemp("tl"), "--tls.set", "B1")


def _scenario(d: pathlib.Path, phases, rules="traffic", duration=45.0):
    (d / "prog.add.xml").write_text(
        '<additional>\n  <tlLogic id="B1" programID="scripted" offset="0" type="static">\n'
        + "".join(f'    <phase duration="{t}" state="{c * N_LINKS}"/>\n' for t, c in phases)
        + "  </tlLogic>\n</additional>\n")
    f = d / f"s_{rules}.toml"
    f.write_text(f'name = "tl"\n[sim]\nnet = "grid.net.xml"\nroutes = ["ego.rou.xml"]\nadditional = ["prog.add.xml"]\n'
                 f'step_s = 0.1\nduration_s = {duration}\nseed = 1\n'
                 f'[ego]\nids = ["ego"]\ncontroller = "scripted"\ncruise_speed_mps = 12.0\nlayers = {[] if rules == "none" else [rules]}\n'
                 f'[controllers.scripted]\nspeed_mps = 12.0\n')
    return scenario.load(f)


def _front_s(res):
    ego = res.traj[res.traj["id"] == "ego"]
    h = ego["heading"].to_numpy()
    front = ego[["x", "y"]].to_numpy() + 2.25 * np.column_stack([np.cos(h), np.sin(h)])
    task = res.tasks["ego"]
    return ego["time_s"].to_numpy(), ego["speed"].to_numpy(), polyline_project_many(task.path, front), task


def test_red_light_stops_before_the_line_and_goes_at_green(grid):
    res = runner.run(_scenario(grid, [(25, "r"), (60, "G")]))
    m = outputs.run_metrics(res)
    t, v, s, task = _front_s(res)
    (link,) = [lk for lk in task.links if lk.tls == "B1"]
    before = t < 25.0
    gap = link.s_stop_m - s[before]
    assert gap.min() >= 0.0, "the front crossed the stop line on red"
    stopped = before & (v < 0.05)
    assert stopped.any() and (link.s_stop_m - s[stopped]).max() <= 2.0  # stopped within 2 m of the line
    assert m["red_light_violations"] == 0 and m["goal_reached"]
    assert [c["state"] for c in m["signal_crossings"]] == ["G"]
    assert m["rules_signal_stops"] == 1


def test_without_the_rules_layer_the_red_is_run_and_counted(grid):
    m = outputs.run_metrics(runner.run(_scenario(grid, [(25, "r"), (60, "G")], rules="none")))
    assert m["red_light_violations"] == 1 and m["signal_crossings"][0]["state"] == "r"


def test_a_yellow_too_late_to_stop_comfortably_is_crossed(grid):
    green = runner.run(_scenario(grid, [(90, "G")]))
    t, v, s, task = _front_s(green)
    (link,) = [lk for lk in task.links if lk.tls == "B1"]
    k = int(np.argmax(s >= link.s_stop_m - 12.0))  # 12 m before the line, at ~12 m/s: 24 m needed at 3 m/s^2
    onset = round(float(t[k]), 1)
    assert v[k] ** 2 / (2 * 3.0) > link.s_stop_m - s[k]
    m = outputs.run_metrics(runner.run(_scenario(grid, [(onset, "G"), (3, "y"), (60, "r")])))
    assert [c["state"] for c in m["signal_crossings"]] == ["y"]
    assert m["red_light_violations"] == 0 and m["goal_reached"]


def test_road_speed_cap_is_the_braking_envelope_of_the_limits_ahead():
    limits = np.array([[0.0, 20.0], [100.0, 10.0], [130.0, 20.0]])
    task = EgoTask("e", np.zeros(2), np.array([[0.0, 0.0], [200.0, 0.0]]), 20.0, (), limits)
    p = RulesParams(comfort_decel_mps2=2.0, speed_factor=1.0)
    assert road_speed_cap(task, 50.0, RulesParams(speed_limits=False)) == math.inf
    assert road_speed_cap(task, 50.0, RulesParams(comfort_decel_mps2=2.0)) == pytest.approx(math.sqrt(300.0))  # on by default
    assert road_speed_cap(task, 50.0, p) == pytest.approx(math.sqrt(10.0**2 + 2 * 2.0 * 50.0))  # 17.32
    assert road_speed_cap(task, 110.0, p) == pytest.approx(10.0)  # on the slow piece
    assert road_speed_cap(task, 0.0, p) == pytest.approx(20.0)  # sqrt(100 + 400) = 22.4 > 20 here
    assert road_speed_cap(task, 50.0, RulesParams(comfort_decel_mps2=2.0, speed_factor=1.2)) == \
        pytest.approx(math.sqrt(12.0**2 + 200.0))


def test_a_junctions_turning_speed_counts_only_when_asked_the_limit_before_it_runs_on():
    # 0-100 m an edge at 20 m/s, 100-120 m a junction's internal lane at 8 m/s (netconvert's turning speed),
    # then an edge at 15 m/s
    limits = np.array([[0.0, 20.0, 0.0], [100.0, 8.0, 1.0], [120.0, 15.0, 0.0]])
    task = EgoTask("e", np.zeros(2), np.array([[0.0, 0.0], [200.0, 0.0]]), 20.0, (), limits)
    legal = RulesParams(comfort_decel_mps2=2.0)
    assert road_speed_cap(task, 110.0, legal) == pytest.approx(math.sqrt(15.0**2 + 2 * 2.0 * 10.0))  # 16.3: 20 runs on
    assert road_speed_cap(task, 90.0, legal) == pytest.approx(math.sqrt(15.0**2 + 2 * 2.0 * 30.0))  # 18.6
    turns = RulesParams(comfort_decel_mps2=2.0, turn_speeds=True)
    assert road_speed_cap(task, 110.0, turns) == pytest.approx(8.0)
    assert road_speed_cap(task, 90.0, turns) == pytest.approx(math.sqrt(8.0**2 + 2 * 2.0 * 10.0))  # 10.2


@pytest.fixture(scope="module")
def stop_grid(tmp_path_factory):
    """The same grid with every junction an all-way stop: B1's links are 'w'."""
    return _grid_net(tmp_path_factory.mktemp("stop"), "-j", "allway_stop")


def _stop_run(d, rules):
    f = d / f"s_{rules}.toml"
    f.write_text(f'name = "stop"\n[sim]\nnet = "grid.net.xml"\nroutes = ["ego.rou.xml"]\nstep_s = 0.1\n'
                 f'duration_s = 30.0\nseed = 1\n[ego]\nids = ["ego"]\ncontroller = "scripted"\n'
                 f'cruise_speed_mps = 12.0\nlayers = {[] if rules == "none" else [rules]}\n[controllers.scripted]\nspeed_mps = 12.0\n')
    res = runner.run(scenario.load(f))
    return res, outputs.run_metrics(res)


@pytest.mark.sumo
def test_all_way_stop_the_ego_stands_at_the_line_then_goes(stop_grid):
    res, m = _stop_run(stop_grid, "traffic")
    (link,) = res.tasks["ego"].links
    assert link.state == "w"
    _, v, s, _ = _front_s(res)
    near = (s > link.s_stop_m - 4.0) & (s < link.s_stop_m)  # stop margin 1 m + zone 3 m before the line
    assert v[near].min() < 0.1 and s.max() > link.s_stop_m + 20.0  # stood there, then went on
    assert m["stop_sign_violations"] == 0 and len(m["stop_crossings"]) == 1 and m["goal_reached"]


@pytest.mark.sumo
def test_without_rules_the_ego_runs_the_stop_sign_and_the_metric_says_so(stop_grid):
    _, m = _stop_run(stop_grid, "none")
    (c,) = m["stop_crossings"]
    assert c["violation"] and c["state"] == "w" and m["stop_sign_violations"] == 1


def _slow_street(d: pathlib.Path, traffic_table: str):
    """A netgenerate 3x3 grid whose streets all have a 30 km/h limit (8.33 m/s); the scripted ego wants 12 m/s."""
    subprocess.run([str(BIN / "netgenerate"), "--grid", "--grid.x-number", "3", "--grid.y-number", "3",
                    "--grid.length", "150", "--default.lanenumber", "1", "--default.speed", "8.33",
                    "--no-turnarounds", "true", "--seed", "1", "-o", str(d / "grid.net.xml")],
                   check=True, capture_output=True)
    (d / "ego.rou.xml").write_text(
        '<routes>\n  <vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="20"/>\n'
        '  <route id="r" edges="A1B1 B1C1"/>\n'
        '  <vehicle id="ego" type="ego_car" route="r" depart="0" departPos="5" departSpeed="0"/>\n</routes>\n')
    f = d / "slow.toml"
    f.write_text('name = "slow"\n[sim]\nnet = "grid.net.xml"\nroutes = ["ego.rou.xml"]\nstep_s = 0.1\nduration_s = 40\n'
                 'seed = 1\n[ego]\nids = ["ego"]\ncontroller = "scripted"\ncruise_speed_mps = 12.0\nlayers = ["traffic"]\n'
                 f'[controllers.scripted]\nspeed_mps = 12.0\n{traffic_table}')
    return scenario.load(f)


def test_the_legal_speed_limit_is_kept_by_default(tmp_path):
    """SPEC §5: v <= the lane's limit x speed_factor (1 by default): on a 30 km/h street the ego that wants 12 m/s
    drives at most 8.33 m/s and ``speeding_m`` is 0; with ``speed_limits = false`` it drives 12 m/s and speeds."""
    res = runner.run(_slow_street(tmp_path, ""))
    ego = res.traj[res.traj["id"] == "ego"]
    on_edges = ~ego["lane"].astype(str).str.startswith(":")
    assert ego["speed"][on_edges].max() <= 8.33 + 1e-6
    assert ego["speed"][on_edges].max() >= 8.0  # it does drive at the limit
    assert outputs.run_metrics(res)["speeding_m"] == 0.0
    (tmp_path / "off").mkdir()
    off = runner.run(_slow_street(tmp_path / "off", "[layers.traffic]\nspeed_limits = false\n"))
    assert off.traj[off.traj["id"] == "ego"]["speed"].max() >= 11.9
    assert outputs.run_metrics(off)["speeding_m"] > 100.0
