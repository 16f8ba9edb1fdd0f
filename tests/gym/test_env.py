"""The Gymnasium environment on the overtaking scenario in real SUMO: Gymnasium's own checker, a random
and a scripted episode, determinism, the acceleration/yaw-rate actions, and the same scripted policy
as the ``policy`` controller in ``sumo-avoid run`` giving the same trajectory as through the env."""
from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest
from gymnasium.utils.env_checker import check_env

from sumo_avoid import metrics
from sumo_avoid.control.policy_examples import KeepLane
from sumo_avoid.gym import RewardWeights, SumoAvoidEnv
from tests.conftest import OVERTAKING, ROOT

POLICY = "sumo_avoid.control.policy_examples:KeepLane"


def _episode(env: SumoAvoidEnv, policy, seed: int):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    rewards = []
    while True:
        obs, r, terminated, truncated, info = env.step(policy(obs))
        assert env.observation_space.contains(obs)
        out.append(obs)
        rewards.append(r)
        if terminated or truncated:
            return np.array(out), np.array(rewards), terminated, truncated, info


def test_check_env_passes_without_warnings():
    """Gymnasium's checker, none of its warnings but its advice to normalise a Box action space: the
    actions are in the actuator's units (gymnasium.wrappers.RescaleAction normalises them, docs/gym.md)."""
    env = SumoAvoidEnv(OVERTAKING, duration_s=2.0)
    try:
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            check_env(env, skip_render_check=True)
        assert [str(w.message) for w in said if "symmetric and normalized" not in str(w.message)] == []
    finally:
        env.close()


def test_random_episode_runs_to_its_end_and_is_judged_by_the_metrics():
    env = SumoAvoidEnv(OVERTAKING, duration_s=4.0)
    try:
        env.action_space.seed(0)
        obs, rewards, terminated, truncated, info = _episode(env, lambda _: env.action_space.sample(), seed=2)
        assert truncated and not terminated and info["time_s"] == pytest.approx(4.0)
        assert len(obs) == 40 and np.isfinite(rewards).all()
        ego = env.trajectory().query("is_ego")
        assert len(ego) == 40 and ego["speed"].std() > 0  # SUMO inserts the ego at step 1; random actions vary its speed
        m = metrics.compute(env.run_result())
        assert m["controller"] == "policy" and m["steps"] == 40
    finally:
        env.close()


def test_same_seed_same_episode():
    env = SumoAvoidEnv(OVERTAKING, duration_s=2.0)
    try:
        actions = np.random.default_rng(5).uniform(env.action_space.low, env.action_space.high, (20, 2))
        first = _episode(env, _replay(actions), seed=7)
        again = _episode(env, _replay(actions), seed=7)
        np.testing.assert_array_equal(first[0], again[0])
        np.testing.assert_array_equal(first[1], again[1])
    finally:
        env.close()


def _replay(actions):
    it = iter(actions)
    return lambda _obs: next(it)


def test_scripted_policy_in_run_gives_the_trajectory_of_the_env(tmp_path):
    """KeepLane through the environment and as ``--controller policy`` in ``sumo-avoid run`` (seed 1)."""
    env = SumoAvoidEnv(OVERTAKING, duration_s=15.0)
    try:
        obs, rewards, terminated, truncated, _ = _episode(env, KeepLane(), seed=1)
        ours = env.trajectory()
    finally:
        env.close()
    assert truncated and not terminated
    assert rewards.sum() > 10.0  # about 15 m/s x 15 s of progress at 0.1 per metre, no penalty
    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-m", "sumo_avoid.cli", "run", str(OVERTAKING), "--controller", "policy",
                        "--seed", "1", "--set", "sim.duration_s=15", "--set", f"controllers.policy.policy={POLICY}",
                        "--out", str(out), "--no-plots", "--quiet"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    theirs = pd.read_csv(out / "trajectories.csv", keep_default_na=False)
    assert len(theirs) == len(ours) and (theirs["id"].astype(str).to_numpy() == ours["id"].to_numpy()).all()
    for col in ("step", "x", "y", "vx", "vy", "speed", "heading"):
        np.testing.assert_allclose(theirs[col].to_numpy(float), ours[col].to_numpy(float), rtol=0, atol=1e-6,
                                   err_msg=col)
    ego = ours.query("is_ego")
    assert ego["speed"].iloc[-1] == pytest.approx(15.0, abs=0.5)  # the policy's cruise speed, not the scenario's 22


def test_acceleration_and_yaw_rate_actions_within_the_actuator_limits():
    env = SumoAvoidEnv(OVERTAKING, action="accel_yaw", layers=(), duration_s=2.0)
    try:
        assert env.action_space.high.tolist() == pytest.approx([3.0, 0.8])  # [actuators.kinematic]
        assert env.action_space.low.tolist() == pytest.approx([-8.0, -0.8])
        assert env.scenario.spec.ego.layers == ()
        obs, _ = env.reset(seed=1)
        v0 = obs[0]
        for _ in range(10):
            obs, *_ = env.step(np.array([-2.0, 0.0], np.float32))
        assert obs[0] == pytest.approx(v0 - 2.0, abs=1e-3)  # 1 s at -2 m/s^2
        h0 = obs[2]
        for _ in range(5):
            obs, *_ = env.step(np.array([0.0, 10.0], np.float32))  # clipped to 0.8 rad/s
        # ... and the actuator turns it at max_lat_accel / v = 4 / 20 = 0.2 rad/s at the ego's 20 m/s
        assert obs[2] - h0 == pytest.approx(0.5 * 4.0 / obs[0], abs=0.01)
    finally:
        env.close()


def test_a_contact_ends_the_episode_with_the_collision_penalty():
    env = SumoAvoidEnv(OVERTAKING, layers=(), duration_s=30.0, reward=RewardWeights(collision=50.0))
    try:
        obs, rewards, terminated, truncated, info = _episode(env, lambda _: np.array([30.0, 0.0]), seed=1)
    finally:
        env.close()
    assert terminated and not truncated and info["new_contacts"] >= 1
    assert rewards[-1] < -40.0
