"""The flocking arena in real SUMO (libsumo, nets/arena.net.xml): spawn, walls, obstacles, metrics,
determinism. Small flocks and short runs (the full Table 4 run is `sumo-avoid reproduce table4`)."""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import pytest

from sumo_avoid.runs import outputs as evaluate
from sumo_avoid.actuation.relaxation import relax
from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs import runner
from sumo_avoid.road.walls import outside_distance, random_positions, square
from sumo_avoid.scenario import spec as scenario

SCN = pathlib.Path(__file__).resolve().parents[2] / "scenarios"
FLOCK_KEYS = ("phi_corr", "phi_coll", "phi_wall", "v_vel", "n_disc", "n_min", "mu_speed", "mu_coll", "mu_disc",
              "mu_cluster", "mu_wall", "mu_corr", "mu", "mean_nn_dist_m", "collisions")


def _run(name, *sets, seed=3):
    scn = scenario.load(SCN / name, list(sets), seed=seed)
    res = runner.run(scn)
    return res, evaluate.run_metrics(res)


@pytest.fixture(scope="module")
def small_v4():
    return _run("arena_v4.toml", "arena.n_agents=12", "sim.duration_s=40")


def test_without_noise_the_rescale_rule_caps_speed_at_v_flock():
    """Physics invariant: with the noise off, |v_des| = v_flock and relaxation towards it never
    overshoots, so no recorded speed exceeds v_flock = 4 m/s."""
    res, _ = _run("arena_v4.toml", "arena.n_agents=12", "sim.duration_s=30", "actuators.relaxation.outer_noise_m2ps3=0",
                  "controllers.flocking.gps_sigma_m2ps2=0")
    ego = res.traj[res.traj["is_ego"]]
    assert ego["speed"].max() <= 4.0 + 1e-9
    assert ego[ego["time_s"] > 20.0]["speed"].mean() > 3.0


def test_relaxation_response_hand_values():
    v1, acc = relax([[0.0, 0.0]], [[4.0, 0.0]], tau_s=1.0, max_accel_mps2=6.0, dt_s=0.2)
    np.testing.assert_allclose(v1, [[0.8, 0.0]])  # (4 - 0)/1 * 0.2
    v1, acc = relax([[0.0, 0.0]], [[0.0, 10.0]], tau_s=1.0, max_accel_mps2=6.0, dt_s=0.2)
    np.testing.assert_allclose(acc, [[0.0, 6.0]])  # capped at 6 m/s^2


def test_random_positions_spacing_and_margin():
    walls = square((0, 0), 250.0)
    ob = [np.array([[100.0, 100.0], [150.0, 100.0], [150.0, 150.0], [100.0, 150.0]])]
    p = random_positions(np.random.default_rng(0), 100, walls, ob, min_spacing_m=6.0, margin_m=5.0)
    d = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    assert d.min() >= 6.0
    assert (p >= 5.0).all() and (p <= 245.0).all()
    assert (outside_distance(p, walls, ob) == 0).all()
    q = random_positions(np.random.default_rng(0), 100, walls, ob, min_spacing_m=6.0, margin_m=5.0)
    np.testing.assert_array_equal(p, q)


def test_arena_runs_in_sumo_with_all_metrics(small_v4):
    res, m = small_v4
    ego = res.traj[res.traj["is_ego"]]
    assert ego["id"].nunique() == 12
    assert res.sim_time_s == pytest.approx(40.0, abs=0.3)
    for k in FLOCK_KEYS:
        assert k in m and m[k] is not None, k
    assert 0.0 <= m["mu"] <= 1.0
    # the flock got going at about v_flock (relaxation from rest, tau = 1 s) and stayed in the square;
    # the actuation noise (0.28 m/s kicks per step, sumo_avoid.core.noise) lets single speeds exceed v_flock
    late = ego[ego["time_s"] > 20.0]
    assert 3.0 < late["speed"].mean() <= 4.0 + 0.3
    assert ego["x"].between(-2, 252).all() and ego["y"].between(-2, 252).all()
    assert m["phi_corr"] > 0.3


def test_same_seed_same_metrics(small_v4):
    _, m1 = small_v4
    _, m2 = _run("arena_v4.toml", "arena.n_agents=12", "sim.duration_s=40")
    assert json.dumps(m1, sort_keys=True) == json.dumps(m2, sort_keys=True)


def test_obstacles_are_avoided_and_passed_to_the_run():
    res, m = _run("arena_obstacles.toml", "arena.n_agents=20", "sim.duration_s=60", seed=2)
    assert len(res.scene.obstacles) == 4
    ego = res.traj[res.traj["is_ego"]]
    d = outside_distance(ego[["x", "y"]].to_numpy(), res.scene.walls, res.scene.obstacles)
    assert d.max() < 2.0  # nobody deeper than 2 m into an obstacle or beyond a wall
    assert m["phi_wall"] < 2.0 and m["mu_wall"] > 0.3


def test_arena_keys_validated(tmp_path):
    with pytest.raises(ScenarioError, match="ego.actuator"):
        scenario.load(SCN / "arena_v4.toml", ['ego.actuator="teleport"'])
    with pytest.raises(ScenarioError, match="preset"):
        scenario.load(SCN / "arena_v4.toml", ["controllers.flocking.preset=paper_v5"])
    with pytest.raises(ScenarioError, match="arena"):
        scenario.load(SCN / "arena_v4.toml", ["arena.origin=[1.0]"])


def test_highway_flock_keeps_to_the_road_among_traffic():
    res, m = _run("highway_flock.toml", "sim.duration_s=30", seed=1)
    ego = res.traj[res.traj["is_ego"]]
    assert ego["id"].nunique() == 10
    assert (~res.traj["is_ego"]).any()  # background traffic was there (and recorded)
    assert m["collisions"] == 0  # footprint contacts, egos vs egos and vs background vehicles
    assert m["phi_wall"] < 1.0
    assert m["v_vel"] > 10.0


def test_relaxation_step_adds_the_velocity_kick_before_moving():
    from sumo_avoid.actuation.relaxation import relaxation_step

    # v = 2 m/s along x, v_des the same (no relaxation); kick (0, 1) m/s; dt 0.2 s
    pos, vel, head, speed = relaxation_step(np.zeros((1, 2)), np.array([[2.0, 0.0]]), np.zeros(1),
                                            np.array([[2.0, 0.0]]), 1.0, 6.0, 0.2, kick=np.array([[0.0, 1.0]]))
    np.testing.assert_allclose(vel, [[2.0, 1.0]])
    np.testing.assert_allclose(pos, [[0.4, 0.2]])
    assert head[0] == pytest.approx(math.atan2(1.0, 2.0)) and speed[0] == pytest.approx(math.sqrt(5.0))


def test_the_arena_net_is_a_canvas_its_junctions_are_no_rules():
    """A flock member placed on an edge of nets/arena.net.xml whose route runs into one of its junctions got
    that junction's link, and the rules layer made it give way there to another member (seed 1, N = 100:
    f21 to f41 at n11, 6.8 s; ``yield_crossings`` listed it): in an arena the egos drive free, so their
    tasks carry no junction links and no lane speed limits."""
    res, m = _run("arena_v4.toml", "arena.n_agents=100", "sim.duration_s=10", seed=1)
    assert len(res.tasks) == 100
    assert all(t.links == () and t.speed_limits is None for t in res.tasks.values())
    assert m["rules_yields"] == 0 and m["yield_crossings"] == [] and m["yield_violations"] == 0
