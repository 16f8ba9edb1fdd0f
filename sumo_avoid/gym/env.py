"""``SumoAvoidEnv``: a Gymnasium environment of one ego of a scenario (docs/gym.md).

The agent is the ``policy`` controller (:mod:`sumo_avoid.control.policy`): it sees the observation
vector of :mod:`sumo_avoid.control.policy_obs` from the scenario's sensor and its actions pass the
scenario's layers and actuator, exactly as ``sumo-avoid run`` with ``ego.controller = "policy"``
drives them (:mod:`sumo_avoid.gym.episode`). The reward is :mod:`sumo_avoid.gym.reward`'s.

One environment per process: libsumo runs one simulation per process, so :meth:`reset` ends the
running one and starts the next, and :meth:`close` ends it; several environments at once need
processes (``gymnasium.vector.AsyncVectorEnv``, not ``SyncVectorEnv``).
"""
from __future__ import annotations

import gymnasium
import numpy as np
from gymnasium import spaces

from sumo_avoid.gym.episode import Episode, load, spaces_of
from sumo_avoid.gym.reward import RewardWeights

#: Episode seeds drawn by reset() without a seed lie in [0, SEED_RANGE).
SEED_RANGE = 2**31 - 1


class SumoAvoidEnv(gymnasium.Env):
    """One ego of ``scenario`` (a scenario file) driven by the agent.

    ``ego``: its id (default: the scenario's only ego; the scenario's other egos, if any, are then
    SUMO's traffic); ``action``: "velocity" (default, (v_s, v_d) along and across the route, m/s) or
    "accel_yaw" (m/s^2, rad/s); ``reward``: the weights; ``layers``: the safety layers in order (None:
    the scenario's ``ego.layers``; ``()``: none); ``duration_s``: the episode's length (the scenario's
    ``sim.duration_s`` by default); ``overrides``: more ``KEY=VALUE`` as ``--set`` takes them (e.g.
    ``controllers.policy.k_nearest=4``, ``ego.sensor="radar"``); ``terminate_on_collision``: a contact
    ends the episode. ``reset(seed=N)`` runs with scenario seed N (so it equals ``sumo-avoid run
    --seed N``); without a seed the first episode runs the scenario's seed and later ones draw theirs
    from the environment's random generator."""

    metadata = {"render_modes": []}

    def __init__(self, scenario, ego: str | None = None, *, action: str = "velocity",
                 reward: RewardWeights = RewardWeights(), layers=None, duration_s: float | None = None,
                 overrides=(), terminate_on_collision: bool = True, log_file=None):
        self._load_args = (scenario, tuple(overrides))
        self._options = {"egos": None if ego is None else [ego], "action": action, "layers": layers,
                         "duration_s": duration_s}
        scn = load(scenario, overrides, **self._options)
        if len(scn.spec.ego.ids) != 1:
            raise ValueError(f"{scenario}: SumoAvoidEnv drives one ego; the scenario has {list(scn.spec.ego.ids)}: "
                             "choose one with ego=..., or use SumoAvoidParallelEnv")
        self.ego = scn.spec.ego.ids[0]
        self.scenario = scn
        (olo, ohi), (alo, ahi) = spaces_of(scn)
        self.observation_space = spaces.Box(olo, ohi, dtype=np.float32)
        self.action_space = spaces.Box(alo, ahi, dtype=np.float32)
        self.weights = reward
        self.terminate_on_collision = terminate_on_collision
        self.log_file = log_file
        self.episode: Episode | None = None
        self._seeded = False

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is None and not self._seeded:
            seed = self.scenario.spec.sim.seed
            super().reset(seed=seed)
        elif seed is None:
            seed = int(self.np_random.integers(SEED_RANGE))
        self._seeded = True
        self.close()
        scn = load(*self._load_args, seed=seed, **self._options)
        self.episode = Episode(scn, (self.ego,), self.weights, self.terminate_on_collision, self.log_file)
        obs = self.episode.start()
        if self.ego not in obs:
            raise RuntimeError(f"{scn.path}: ego '{self.ego}' was never driven within the episode (seed {seed})")
        return obs[self.ego], {"seed": seed}

    def step(self, action):
        ep = self.episode
        if ep is None or ep.over or self.ego not in ep.driven():
            raise RuntimeError("the episode is over: call reset()")
        obs, rewards, terminated, truncated, infos = ep.advance({self.ego: action})
        e = self.ego
        return obs[e], rewards[e], bool(terminated[e]), bool(truncated[e]), infos[e]

    def trajectory(self):
        """The current (or last) episode's recording: ``trajectories.csv``'s table."""
        return self.episode.trajectory() if self.episode is not None else None

    def run_result(self):
        """The last finished episode as a :class:`~sumo_avoid.rollout.result.RunResult` (``metrics.compute``
        judges it as a run), None while it goes on."""
        return self.episode.result if self.episode is not None else None

    def close(self):
        if self.episode is not None:
            self.episode.close()
