"""Radar + danger-time layer in the loop, on real libsumo runs (short scenarios)."""
import pathlib
import re

import pytest

from sumo_avoid.runs import outputs as evaluate
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario

SCN = pathlib.Path(__file__).resolve().parents[2] / "scenarios"


def radar_brake(tmp_path, speed_mps: float, safety: str):
    """radar_brake with lead and ego at ``speed_mps`` and the stopped car placed so that the lead
    cuts out in front of it ~18 s in (as in the 100 km/h file)."""
    xml = (SCN / "radar_brake.rou.xml").read_text()
    xml = re.sub(r'(id="lead_car".*?maxSpeed=")[0-9.]+', rf"\g<1>{speed_mps}", xml)
    xml = xml.replace('departSpeed="27.78"', f'departSpeed="{speed_mps}"')
    stop = 100 + round(18 * speed_mps)
    xml = xml.replace('departPos="600"', f'departPos="{stop}"').replace('endPos="600"', f'endPos="{stop}"')
    rou = tmp_path / f"radar_brake_{speed_mps}.rou.xml"
    rou.write_text(xml)
    scn = scenario.load(SCN / "radar_brake.toml", [f"sim.routes=['{rou}']", f"controllers.scripted.speed_mps={speed_mps}",
                                                   f"ego.layers={['traffic'] + ([safety] if safety != 'none' else [])}", "sim.duration_s=28"])
    return evaluate.run_metrics(runner.run(scn))


@pytest.mark.parametrize("kmh", [50, 80, 100])
def test_radar_brake_danger_time_layer_stops_in_time(tmp_path, kmh):
    m = radar_brake(tmp_path, round(kmh / 3.6, 2), "danger_time")
    assert m["collisions"] == 0 and m["sumo_collisions"] == 0
    assert m["radar_brakes"] >= 1
    assert m["min_danger_time_s"] < 3.0  # the hidden car was a real threat
    assert m["min_gap_m"] > 0.5


def test_radar_brake_without_the_layer_crashes_at_100(tmp_path):
    m = radar_brake(tmp_path, 27.78, "none")
    assert m["collisions"] >= 1


# Issue acceptance: on radar alone (front radar + tracker memory, no ground truth) APF-SA gets
# past the six vehicles without contact on each of 10 seeds. Two fixes got it there, both about
# which way a radar return is taken to move (the radial speed alone does not say): along the
# route at the ego, not the ego's momentary heading, (1) for the boxes the controller avoids (seed
# 1 pulled out at 2 m/s in front of car2 closing at 13 m/s) and (2) for coasting remembered
# returns (seed 7 steered into car3 beside it, whose coasted track had drifted sideways).
RADAR_SEEDS = (1, 3, 7)


@pytest.mark.parametrize("seed", RADAR_SEEDS)
def test_overtaking_on_radar_reaches_goal(seed):
    """Seeds 1 and 7 are the two that collided before the fixes above; seed 3 passed closest (0.43 m)
    in the 10-seed study. All 10 seeds, truth beside radar, are a study, not a test
    (reports/radar_study/overtaking_front.csv):
    ``python -m sumo_avoid.studies.radar_study scenarios/overtaking.toml --seeds 1-10
    --csv reports/radar_study/overtaking_front.csv``."""
    scn = scenario.load(SCN / "overtaking.toml", ['ego.sensor="radar"'], seed=seed)
    m = evaluate.run_metrics(runner.run(scn))
    assert "radar_warnings" in m and "min_danger_time_s" in m
    assert m["goal_reached"] and m["collisions"] == 0


def test_overtaking_with_a_rear_radar_too():
    """The optional rear radar (one fused tracker memory) on the seed that pulled out in front of
    car2: no contact, and the run logs returns of both mounts."""
    scn = scenario.load(SCN / "overtaking.toml", ['ego.sensor="radar"', "sensors.radar.rear=true",
                                                   "sensors.radar.log_detections=true"], seed=1)
    res = runner.run(scn)
    m = evaluate.run_metrics(res)
    assert m["goal_reached"] and m["collisions"] == 0
    assert set(res.tables["detections"]["mount"]) == {"front", "rear"}


def test_cut_in_with_layer_no_collision():
    scn = scenario.load(SCN / "cut_in.toml", ['ego.controller="scripted"', "controllers.scripted.speed_mps=25",
                                              "sim.duration_s=15"])
    m = evaluate.run_metrics(runner.run(scn))
    assert m["collisions"] == 0 and m["radar_brakes"] >= 1
