"""Bad input through the real CLI: exit code 2, one line on stderr naming file and key, no traceback,
nothing written; and a good run writes its outputs."""
import json
import math
import pathlib
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, SCENARIOS, cli_in_process

NETS = ROOT / "nets"

GOOD = (SCENARIOS / "overtaking.toml").read_text()


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "sumo_avoid.cli", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd)


def write(tmp_path, text, name="bad.toml"):
    p = SCENARIOS / f"_tmp_{tmp_path.name}_{name}"
    p.write_text(text)
    return p


CASES = {
    "syntax": (GOOD.replace('name = "overtaking"', 'name = "overtaking'), "<syntax>", "valid TOML"),
    "unknown_key": (GOOD.replace("[ego]", "[ego]\nspeeed = 3"), "ego.speeed", "known keys"),
    "wrong_type": (GOOD.replace("duration_s = 120.0", 'duration_s = "long"'), "sim.duration_s", "a number"),
    "negative": (GOOD.replace("cruise_speed_mps = 22.0", "cruise_speed_mps = -5.0"), "ego.cruise_speed_mps",
                 "non-negative"),
    "nan": (GOOD.replace("max_accel_mps2 = 3.0", "max_accel_mps2 = nan"), "actuators.kinematic.max_accel_mps2", "finite"),
    "layer": (GOOD.replace("[ego]", '[ego]\nlayers = ["traffic", "hope"]'), "ego.layers[1]", "one of"),
    "layer_param": (GOOD + "\n[layers.danger_time]\nwarning_s = -1.0\n", "layers.danger_time.warning_s", "non-negative"),
    "old_actuator": (GOOD.replace("[actuators.kinematic]", "[actuator]"), "key 'actuator'", "was renamed: use [actuators.kinematic]"),
    "old_ego_rules": (GOOD.replace("[ego]", '[ego]\nrules = "none"'), "key 'ego.rules'", "was renamed: use ego.layers"),
    "controller": (GOOD.replace('controller = "apf_sa"', 'controller = "magic"'), "ego.controller", "one of"),
    "missing_net": (GOOD.replace("overtaking.net.xml", "nowhere.net.xml"), "sim.net", "existing SUMO network"),
    "missing_routes": (GOOD.replace('routes = ["overtaking.rou.xml"]', 'routes = ["nowhere.rou.xml"]'),
                       "sim.routes[0]", "existing SUMO route"),
    "goal_off_net": (GOOD.replace("goal_tolerance_m = 5.0", "goal_tolerance_m = 5.0\ngoal = [500.0, 300.0]"),
                     "ego.goal", "drivable area"),
    "param_negative": (GOOD + "\n[controllers.apf_sa]\nk_rep = -1.0\n", "controllers.apf_sa.k_rep", "non-negative"),
    "goal_edge_unknown": (GOOD.replace("goal_tolerance_m = 5.0", 'goal_tolerance_m = 5.0\ngoal = "nowhere"'),
                          "ego.goal", "an edge id of the network"),
    "goals_unknown_ego": (GOOD + '\n[ego.goals]\nnobody = "road"\n', "ego.goals.nobody", "an ego id"),
    "goals_bad_point": (GOOD + "\n[ego.goals]\nego = [1.0, 2.0, 3.0]\n", "ego.goals.ego", "[x, y] or an edge id"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_scenario_exits_2_with_one_line(tmp_path, case):
    text, key, expected = CASES[case]
    path = write(tmp_path, text, f"{case}.toml")
    out = tmp_path / "out"
    try:
        r = cli_in_process("run", path, "--out", out)
    finally:
        path.unlink()
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert str(path) in lines[0] and key in lines[0] and expected in lines[0]
    assert "Traceback" not in r.stderr
    assert not out.exists()


def test_bad_override_and_missing_file(tmp_path):
    r = cli_in_process("run", SCENARIOS / "overtaking.toml", "--set", "sim.step_s=-1", "--out", tmp_path / "o")
    assert r.returncode == 2 and "sim.step_s" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    r = cli("run", tmp_path / "none.toml")  # one case through a real process: nothing but our line
    assert r.returncode == 2 and "none.toml" in r.stderr
    assert not (tmp_path / "o").exists()


def test_run_writes_outputs(tmp_path):
    out = tmp_path / "run"
    r = cli("run", SCENARIOS / "left_turn.toml", "--out", out, "--set", "sim.duration_s=20", "--quiet")
    assert r.returncode == 0, r.stderr
    m = json.loads((out / "metrics.json").read_text())
    for key in ("collisions", "sumo_collisions", "min_gap_m", "phi_coll", "phi_wall", "goal_reached",
                "time_to_goal_s", "path_length_m", "mean_speed_mps"):
        assert key in m
    assert m["sim_time_s"] == pytest.approx(20.0, abs=0.11)
    traj = pd.read_csv(out / "trajectories.csv")
    assert traj["heading"].gt(-math.pi).all() and traj["heading"].le(math.pi).all()
    west = traj[traj["id"] == "cross1"]  # E2C -> C2W: SUMO's compass 270 deg was written as -pi before
    assert np.allclose(west["heading"].abs(), math.pi, atol=0.05) and west["heading"].gt(0).any()
    n = sum(ln.startswith("Warning: ") for ln in (out / "sumo.log").read_text().splitlines())
    assert r.stdout.strip().splitlines()[-1].strip() == f"sumo.log: {n} warning{'' if n == 1 else 's'}"
    assert "Warning: " not in r.stderr
    assert (out / "trajectory.png").stat().st_size > 20_000
    assert (out / "trajectories.csv").stat().st_size > 0
    assert "collisions" in r.stdout
    assert not any(k.endswith(("wall_s", "_clock", "elapsed_s")) or k in ("loop_s", "total_s") for k in m)


def test_route_file_sumo_cannot_load(tmp_path):
    routes = SCENARIOS / f"_tmp_{tmp_path.name}.rou.xml"
    routes.write_text('<routes>\n  <vehicle id="ego" route="nope" depart="0"/>\n</routes>\n')
    path = write(tmp_path, GOOD.replace("overtaking.rou.xml", routes.name), "sumo_bad.toml")
    out = tmp_path / "out"
    try:
        r = cli("run", path, "--out", out)
    finally:
        path.unlink()
        routes.unlink()
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "'sim.routes[0]'" in r.stderr and "nope" in r.stderr
    assert f"{routes}, vehicle 'ego'" in r.stderr
    assert not out.exists()


def test_an_unknown_edge_in_a_trip_names_the_route_file_and_the_trip(tmp_path):
    """SUMO's message names the trip, not the file: the line names the file that defines it."""
    (tmp_path / "types.rou.xml").write_text('<routes>\n  <vType id="car" length="4.5"/>\n</routes>\n')
    (tmp_path / "trips.rou.xml").write_text('<routes>\n  <trip id="ego" type="car" from="road" to="road" depart="0"/>\n'
                                            '  <trip id="t7" type="car" from="nope" to="road" depart="1"/>\n</routes>\n')
    path = tmp_path / "trip.toml"
    path.write_text(f'name = "trip"\n[sim]\nnet = "{NETS / "overtaking.net.xml"}"\n'
                    'routes = ["types.rou.xml", "trips.rou.xml"]\n[ego]\nids = ["ego"]\n')
    out = tmp_path / "out"
    r = cli_in_process("run", path, "--out", out)
    assert r.returncode == 2
    line, = r.stderr.strip().splitlines()
    assert line == (f"sumo-avoid: error: {path}: key 'sim.routes[1]': expected a file SUMO can load: "
                    f"{tmp_path / 'trips.rou.xml'}, trip 't7': its from edge 'nope' is not in the network "
                    f"{NETS / 'overtaking.net.xml'}")  # found before SUMO starts (sumo/inputs.py)
    assert not out.exists()


def _road_scenario(tmp_path, name: str, vehicles: str, ego_ids) -> pathlib.Path:
    """A 3 s scenario on the overtaking road with the given route-file elements and egos."""
    (tmp_path / "r.rou.xml").write_text(f"<routes>\n  {vehicles}\n</routes>\n")
    path = tmp_path / f"{name}.toml"
    ids = ", ".join(f'"{v}"' for v in ego_ids)
    path.write_text(f'name = "{name}"\n[sim]\nnet = "{NETS / "overtaking.net.xml"}"\nroutes = ["r.rou.xml"]\n'
                    f'duration_s = 3.0\n[ego]\nids = [{ids}]\n')
    return path


def test_an_ego_that_never_departs_exits_2_and_writes_nothing(tmp_path):
    path = _road_scenario(tmp_path, "late", '<trip id="ego" from="road" to="road" depart="0"/>\n'
                          '  <trip id="late" from="road" to="road" depart="5"/>', ["ego", "late"])
    out = tmp_path / "out"
    out.mkdir()  # an existing folder stays as it was: empty
    r = cli_in_process("run", path, "--out", out, "--quiet")  # found from the route file, before SUMO starts
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().splitlines() == [
        (f"sumo-avoid: error: {path}: key 'ego.ids[1]': expected egos that depart within the run: 'late' departs "
         "at t=5 s, the run ends at sim.duration_s = 3 s")]
    assert list(out.iterdir()) == []
    r = cli("run", path, "--out", tmp_path / "ok", "--quiet", "--no-plots", "--set", "sim.duration_s=6")
    assert r.returncode == 0, r.stderr  # it departs at 5 s: a normal run


def test_input_sumo_rejects_only_mid_run_exits_2_naming_the_file_and_writes_nothing(tmp_path):
    """An invalid departLane passes SUMO's load and would stop it only when it inserts the vehicle:
    it is found before SUMO starts."""
    path = _road_scenario(tmp_path, "lane", '<trip id="ego" from="road" to="road" depart="1" departLane="7"/>', ["ego"])
    out = tmp_path / "out"
    r = cli_in_process("run", path, "--out", out, "--quiet")
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"sumo-avoid: error: {path}: key 'sim.routes[0]': "), lines
    assert "departLane 7 does not exist" in lines[0] and "trip 'ego'" in lines[0]
    assert not out.exists()


def test_sumo_warnings_go_to_sumo_log_and_are_counted(tmp_path):
    """crash_straight: SUMO warns of the commanded collision; the line is in sumo.log, not on the
    terminal, and the run ends with the count."""
    out = tmp_path / "crash"
    r = cli("run", SCENARIOS / "crash_straight.toml", "--out", out, "--quiet", "--no-plots")
    assert r.returncode == 0, r.stderr
    log = (out / "sumo.log").read_text()
    warnings = [ln for ln in log.splitlines() if ln.startswith("Warning: ")]
    assert len(warnings) == 1 and "collision with vehicle 'parked'" in warnings[0]
    assert "Warning" not in r.stderr
    assert r.stdout.strip().splitlines()[-1].strip() == "sumo.log: 1 warning"
