"""ga_planner on real SUMO in the radar-revealed field (scenarios/planner/field.toml), against the
shortest collision-free path a visibility graph finds on the full map (which the planner never
sees: it has only its radar)."""
import json

import numpy as np
import pytest
from conftest import run_scenario

from sumo_avoid.runs.outputs import write_outputs
from sumo_avoid.planning.reference import crosses, shortest_path
from sumo_avoid.plots.planner import parse_path


def test_visibility_graph_reference_round_a_square():
    square = np.array([[4.0, -1.0], [6.0, -1.0], [6.0, 1.0], [4.0, 1.0]])
    L, path = shortest_path((0, 0), (10, 0), [square], 0.0)
    assert L == pytest.approx(2 * np.hypot(4, 1) + 2)  # over a corner, along the side, down again
    assert not crosses(path, [square]) and crosses([[0, 0], [10, 0]], [square])
    L1, _ = shortest_path((0, 0), (10, 0), [square], 1.0)  # grown by 1 m (mitred): corners at (3, -2), (7, -2)
    assert L1 == pytest.approx(2 * np.hypot(3, 2) + 4)


@pytest.fixture(scope="module")
def field_run():
    return run_scenario("planner/field", seed=1)


def test_field_goal_reached_without_contact_on_a_short_path(field_run):
    res, m = field_run
    assert m["goal_reached"] is True
    assert m["collisions"] == 0
    assert m["phi_wall"] == 0.0 and m["off_road_m"] == 0.0  # never inside an obstacle or past a wall
    ego = res.traj[res.traj["id"] == "ego"].sort_values("step")
    ref, _ = shortest_path(ego[["x", "y"]].to_numpy()[0], res.goals["ego"], res.scene.obstacles, 0.9)
    assert m["path_length_m"] <= 1.2 * ref


def test_field_plan_log_and_metrics(field_run, tmp_path):
    res, m = field_run
    plans = res.tables["plans"]
    assert plans["trigger"].iloc[0] == "takeover" and m["plans"] == len(plans) >= 2
    assert m["replans"] == int((plans["trigger"] != "takeover").sum())
    assert set(plans["trigger"]) <= {"takeover", "new_obstacle", "clearance", "blocked"}
    assert (plans["generation_usable"].between(0, 20)).mean() >= 0.95  # the seed: usable within ~20 generations
    for row in plans.itertuples():  # each logged path starts where the ego was and ends at the goal
        path = parse_path(row.path)
        assert np.allclose(path[-1], res.goals["ego"], atol=1e-3)
        assert len(row.best_fitness.split(";")) == row.generations + 1
    known = res.tables["radar_map"]
    assert known["is_return"].any() and (np.diff(plans["known_points"]) >= 0).all()
    out = tmp_path / "run"
    write_outputs(res, out)
    for name in ("plans.csv", "radar_map.csv", "plans.png", "convergence.png"):
        assert (out / name).stat().st_size > 0
    timings = json.loads((out / "timings.json").read_text())
    assert timings["plan_ms_max"] >= timings["plan_ms_mean"] > 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert "plan_ms_mean" not in metrics and metrics["plans"] == len(plans)


def test_without_radar_range_the_planner_knows_nothing():
    """The planner sees only radar returns: with a 1 m radar every plan runs straight through the
    first obstacle, and only the danger-time layer (same radar, standstill gap) stops the car."""
    res, m = run_scenario("planner/field", seed=1, overrides=["sensors.radar.max_range_m=1.0", "sim.duration_s=12"])
    paths = [parse_path(p) for p in res.tables["plans"]["path"]]
    assert paths and all(crosses(p, res.scene.obstacles) for p in paths)
    assert m["goal_reached"] is False and m["radar_brakes"] >= 1


def test_same_seed_same_plans_and_metrics():
    runs = [run_scenario("planner/field", seed=2, overrides=["sim.duration_s=6"]) for _ in range(2)]
    (ra, ma), (rb, mb) = runs
    assert json.dumps(ma, sort_keys=True) == json.dumps(mb, sort_keys=True)
    cols = ["time_s", "trigger", "generations", "generation_usable", "best_fitness", "path"]  # not plan_ms
    assert ra.tables["plans"][cols].equals(rb.tables["plans"][cols]) and len(ra.tables["plans"]) >= 1
