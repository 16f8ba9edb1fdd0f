"""The PettingZoo ParallelEnv on the highway flock in real SUMO: PettingZoo's own API test, every
flock member an agent, and a seeded episode repeated exactly."""
from __future__ import annotations

import numpy as np
from pettingzoo.test import parallel_api_test

from sumo_avoid.gym import SumoAvoidParallelEnv
from tests.conftest import SCENARIOS

FLOCK = SCENARIOS / "highway_flock.toml"


def test_parallel_api_test_passes_on_the_highway_flock():
    env = SumoAvoidParallelEnv(FLOCK, duration_s=1.5)
    try:
        parallel_api_test(env, num_cycles=100)
    finally:
        env.close()


def test_every_flock_member_is_an_agent_and_a_seeded_episode_repeats():
    env = SumoAvoidParallelEnv(FLOCK, duration_s=1.0)
    try:
        def episode():
            obs, _ = env.reset(seed=3)
            assert env.agents == [f"flock{k}" for k in range(10)]
            seen = [np.stack([obs[a] for a in env.agents])]
            total = dict.fromkeys(env.agents, 0.0)
            while env.agents:
                obs, rew, term, trunc, _ = env.step({a: np.array([14.0, 0.0]) for a in env.agents})
                seen.append(np.stack(list(obs.values())))
                for a, r in rew.items():
                    total[a] += r
            return np.concatenate(seen), total

        first, reward = episode()
        again, reward_again = episode()
        np.testing.assert_array_equal(first, again)
        assert reward == reward_again and all(r > 0 for r in reward.values())  # progress along the road
        assert len(first) == 10 * 10  # SUMO inserts the flock at step 1: reset, then steps 1..9 of 10
    finally:
        env.close()
