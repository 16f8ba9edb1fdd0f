"""Danger-time layer: t_d against hand-computed values, levels, limits, counters, scenario keys."""
import math

import numpy as np
import pytest

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.core.types import Detections
from sumo_avoid.safety.danger_time import (
    BRAKE,
    NONE,
    REDUCE,
    WARNING,
    DangerTimeLayer,
    DangerTimeParams,
    danger_time,
    levels,
)
from sumo_avoid.scenario import spec as scenario

P = DangerTimeParams()
W = np.array([1.8, 1.8])


def dets(rows, n_ego=2):
    """rows: (ego index, range, azimuth deg, radial speed)."""
    a = np.array(rows, float).reshape(-1, 4)
    return Detections(0.0, tuple(f"e{i}" for i in range(n_ego)), np.zeros((n_ego, 2)), np.zeros(n_ego),
                      np.zeros((n_ego, 2)), a[:, 0].astype(int), a[:, 1], np.radians(a[:, 2]), a[:, 3],
                      tuple("t" for _ in range(len(a))))


def test_danger_time_hand_computed():
    # e0: 40 m ahead closing at 10 m/s -> 4 s; 30 m closing at 20 -> 1.5 s (the minimum);
    #     a receding target and one 30 deg to the side (y = 15 m, out of the path) do not count
    # e1: nothing closing -> inf, but its in-path gap is 12 m
    d = dets([(0, 40, 0, -10), (0, 30, 1, -20), (0, 10, 0, +3), (0, 30, 30, -30), (1, 12, 0, 1.0)])
    td, vc, gap = danger_time(d, W, 0.5)
    assert td[0] == pytest.approx(1.5)
    assert vc[0] == pytest.approx(20.0)
    assert gap[0] == pytest.approx(10.0)
    assert math.isinf(td[1]) and vc[1] == 0 and gap[1] == pytest.approx(12.0)


def test_levels_thresholds_and_kinematic_braking():
    td = np.array([5.0, 2.9, 1.9, 0.9, 2.5])
    vc = np.array([5.0, 5.0, 5.0, 5.0, 30.0])  # 30 m/s: brake below 30/12 + 0.3 = 2.8 s
    np.testing.assert_array_equal(levels(td, vc, P), [NONE, WARNING, REDUCE, BRAKE, BRAKE])
    np.testing.assert_array_equal(levels(np.array([np.inf]), np.zeros(1), P, gap=np.array([1.5])), [BRAKE])


def test_layer_limits_velocity_counts_episodes_and_releases_when_clear():
    layer = DangerTimeLayer(P)
    v = np.array([[20.0, 0.0], [20.0, 0.0]])
    speed = np.array([20.0, 20.0])
    # e0 at 2.5 s: warning only (brake below 20/12 + 0.3 = 1.97 s; 2.5 < 3) -> unchanged;
    # e1 at 1.8 s <= 1.97 s: full braking -> zero
    out, lvl = layer.apply(v, dets([(0, 50, 0, -20), (1, 36, 0, -20)]), W, speed, 0.1)
    np.testing.assert_array_equal(lvl, [WARNING, BRAKE])
    np.testing.assert_allclose(out, [[20.0, 0.0], [0.0, 0.0]])
    # e0 at 1.99 s with closing 10 m/s (brake below max(1, 10/12+0.3) = 1.13 s): reduce at 3 m/s^2
    out, lvl = layer.apply(v, dets([(0, 19.9, 0, -10)]), W, speed, 0.1)
    assert lvl[0] == REDUCE
    np.testing.assert_allclose(out[0], [20.0 - 0.3, 0.0])
    assert lvl[1] == NONE  # e1: nothing in range any more -> released
    out, lvl = layer.apply(v, dets([], n_ego=2), W, speed, 0.1)  # nothing in range: pass through
    np.testing.assert_allclose(out, v)
    np.testing.assert_array_equal(lvl, [NONE, NONE])
    st = layer.stats()
    assert st["radar_warnings"] == 2 and st["radar_reductions"] == 2 and st["radar_brakes"] == 1
    assert st["min_danger_time_s"] == pytest.approx(1.8)


def test_brake_is_held_until_the_danger_has_passed():
    layer = DangerTimeLayer(P)
    v, speed = np.array([[20.0, 0.0]]), np.array([20.0])
    _, lvl = layer.apply(v, dets([(0, 20, 0, -20)], 1), W[:1], speed, 0.1)  # 1 s: brake
    assert lvl[0] == BRAKE
    _, lvl = layer.apply(v, dets([(0, 18, 0, -8)], 1), W[:1], speed, 0.1)  # 2.25 s: still braking
    assert lvl[0] == BRAKE
    _, lvl = layer.apply(v, dets([(0, 30, 0, -5)], 1), W[:1], speed, 0.1)  # 6 s: released
    assert lvl[0] == NONE
    assert layer.stats()["radar_brakes"] == 1


def test_params_validation():
    with pytest.raises(ValueError):
        DangerTimeParams(warning_s=1.0, reduce_s=2.0)


def test_scenario_keys(tmp_path):
    src = (scenario.pathlib.Path(__file__).resolve().parents[2] / "scenarios" / "radar_brake.toml")
    scn = scenario.load(src, ["sensors.radar.max_range_m=80", "layers.danger_time.warning_s=4.0"])
    assert scn.spec.ego.sensor == "radar" and scn.spec.ego.layers == ("traffic", "danger_time")
    assert scn.table("sensors.radar").max_range_m == 80.0 and scn.table("layers.danger_time").warning_s == 4.0
    for bad in ('ego.sensor="lidar"', 'ego.layers=["traffic", "aeb"]', "sensors.radar.fov_deg=270",
                "layers.danger_time.brake_s=9", "sensors.radar.colour=1", 'ego.layers="danger_time"',
                'ego.layers=["traffic", "traffic"]', "sensors.lidar.range_m=3", "sensors.truth.x=1"):
        with pytest.raises(ScenarioError):
            scenario.load(src, [bad])
