"""``SumoAvoidParallelEnv``: a PettingZoo ``ParallelEnv`` of every ego of a scenario (a flock, a
formation's members), each an agent with the observation, action and reward of
:class:`~sumo_avoid.gym.env.SumoAvoidEnv` (docs/gym.md).

The agents are the egos the controller drives: :meth:`reset` steps the simulation until every ego
has departed; an agent leaves ``agents`` when it is retired (at its goal, or gone from the network),
on a contact (``terminate_on_collision``) -- its car is then held at its speed along the route until
the run ends -- or when the episode's time is up. One environment per process, as for
:class:`~sumo_avoid.gym.env.SumoAvoidEnv`.
"""
from __future__ import annotations

import functools

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from sumo_avoid.gym.episode import Episode, load, spaces_of
from sumo_avoid.gym.env import SEED_RANGE
from sumo_avoid.gym.reward import RewardWeights


class SumoAvoidParallelEnv(ParallelEnv):
    """Every ego of ``scenario`` driven by its agent; options as :class:`~sumo_avoid.gym.env.SumoAvoidEnv`'s."""

    metadata = {"render_modes": [], "name": "sumo_avoid_parallel_v0"}

    def __init__(self, scenario, *, action: str = "velocity", reward: RewardWeights = RewardWeights(), layers=None,
                 duration_s: float | None = None, overrides=(), terminate_on_collision: bool = True, log_file=None):
        self._load_args = (scenario, tuple(overrides))
        self._options = {"action": action, "layers": layers, "duration_s": duration_s}
        scn = load(scenario, overrides, **self._options)
        if scn.spec.arena is not None:
            self.possible_agents = list(scn.spec.arena.ids)
        else:
            self.possible_agents = list(scn.spec.ego.ids)
        self.scenario = scn
        (olo, ohi), (alo, ahi) = spaces_of(scn)
        self._obs_space = spaces.Box(olo, ohi, dtype=np.float32)
        self._act_space = spaces.Box(alo, ahi, dtype=np.float32)
        self.weights, self.terminate_on_collision, self.log_file = reward, terminate_on_collision, log_file
        self.agents: list[str] = []
        self.episode: Episode | None = None
        self._rng: np.random.Generator | None = None

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent):
        return self._obs_space

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent):
        return self._act_space

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is None and self._rng is None:
            seed = self.scenario.spec.sim.seed
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        else:
            seed = int(self._rng.integers(SEED_RANGE))
        self.close()
        scn = load(*self._load_args, seed=seed, **self._options)
        self.episode = Episode(scn, self.possible_agents, self.weights, self.terminate_on_collision, self.log_file)
        obs = self.episode.start()
        self.agents = [a for a in self.possible_agents if a in obs]
        return {a: obs[a] for a in self.agents}, {a: {"seed": seed} for a in self.agents}

    def step(self, actions: dict):
        if self.episode is None or not self.agents:
            raise RuntimeError("the episode is over: call reset()")
        obs, rewards, terminated, truncated, infos = self.episode.advance(
            {a: act for a, act in actions.items() if a in self.agents})
        live = self.agents
        obs = {a: obs[a] for a in live}
        self.agents = [a for a in live if not (terminated[a] or truncated[a])]
        return (obs, {a: rewards[a] for a in live}, {a: bool(terminated[a]) for a in live},
                {a: bool(truncated[a]) for a in live}, {a: infos[a] for a in live})

    def trajectory(self):
        """The current (or last) episode's recording: ``trajectories.csv``'s table."""
        return self.episode.trajectory() if self.episode is not None else None

    def close(self):
        if self.episode is not None:
            self.episode.close()
