"""Bad input through the real CLI: exit code 2, one line on stderr naming file and key, no traceback,
nothing written; and a good run writes its outputs."""
import json
import subprocess
import sys

import pytest
from conftest import SCENARIOS, cli_in_process

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
    "nan": (GOOD.replace("max_accel_mps2 = 3.0", "max_accel_mps2 = nan"), "actuator.max_accel_mps2", "finite"),
    "controller": (GOOD.replace('controller = "apf_sa"', 'controller = "magic"'), "ego.controller", "one of"),
    "missing_net": (GOOD.replace("overtaking.net.xml", "nowhere.net.xml"), "sim.net", "existing SUMO network"),
    "missing_routes": (GOOD.replace('routes = ["overtaking.rou.xml"]', 'routes = ["nowhere.rou.xml"]'),
                       "sim.routes[0]", "existing SUMO route"),
    "goal_off_net": (GOOD.replace("goal_tolerance_m = 5.0", "goal_tolerance_m = 5.0\ngoal = [500.0, 300.0]"),
                     "ego.goal", "drivable area"),
    "param_negative": (GOOD + "\n[controllers.apf_sa]\nk_rep = -1.0\n", "controllers.apf_sa.k_rep", "non-negative"),
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
    assert len(r.stderr.strip().splitlines()) == 1 and "'sim'" in r.stderr and "nope" in r.stderr
    assert not out.exists()
