"""One episode of a scenario stepped by an agent: the run's own pieces (:class:`~sumo_avoid.runs.runner.OpenRun`,
the loop's halves :func:`~sumo_avoid.rollout.loop.perceive` and :func:`~sumo_avoid.rollout.loop.act`)
with the ``policy`` controller whose actions come from the agent (:class:`AgentController`), so that
an episode is exactly a ``sumo-avoid run`` of that controller: same sensor, layers, actuator, recording.

libsumo runs one simulation per process: :meth:`Episode.close` ends it, a new :class:`Episode` starts
the next one.
"""
from __future__ import annotations

import json

import numpy as np

from sumo_avoid.control.policy import PolicyController, PolicyParams, action_bounds, kinematic_limits
from sumo_avoid.control.policy_obs import bounds
from sumo_avoid.gym.reward import RewardTracker, RewardWeights
from sumo_avoid.rollout.loop import act, perceive
from sumo_avoid.runs.runner import OpenRun, scenario_errors
from sumo_avoid.scenario import spec as scenario


class AgentController(PolicyController):
    """The ``policy`` controller driven by the agent: its actions are ``pending`` (ego id -> action);
    an ego without one holds its speed along the route (velocity) or its speed and heading (accel_yaw)."""

    def __init__(self, params: PolicyParams, ctx=None):
        super().__init__(params, ctx, policy=self.hold)
        self.pending: dict[str, np.ndarray] = {}

    def hold(self, x: np.ndarray) -> np.ndarray:
        return np.array([x[3], 0.0]) if self.p.action == "velocity" else np.zeros(2)

    def decide(self, ego_ids, x):
        return np.array([self.pending[v] if v in self.pending else self.hold(row)
                         for v, row in zip(ego_ids, x)], float).reshape(-1, 2)


def load(path, overrides=(), *, egos=None, action: str | None = None, layers=None, duration_s=None, seed=None):
    """The scenario of an environment: ``path`` with ``overrides`` (``--set``'s KEY=VALUE), the ``policy``
    controller, and the environment's options as overrides (``egos`` the ego ids, ``action``, ``layers``
    the safety layers in order, ``duration_s``)."""
    more = list(overrides)
    if egos is not None:
        more.append(f"ego.ids={json.dumps(list(egos))}")
    if action is not None:
        more.append(f"controllers.policy.action={json.dumps(action)}")
    if layers is not None:
        more.append(f"ego.layers={json.dumps(list(layers))}")
    if duration_s is not None:
        more.append(f"sim.duration_s={float(duration_s)!r}")
    return scenario.load(path, more, controller="policy", seed=seed)


def spaces_of(scn) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """((obs low, high), (action low, high)) float32 of a scenario loaded by :func:`load`."""
    params = scn.params
    return bounds(params), action_bounds(params, kinematic_limits(scn.tables))


class Episode:
    """One simulation of ``scn`` (loaded by :func:`load`) stepped by an agent for the egos ``agents``.

    :meth:`start` steps until every agent is driven (or the run is over) and returns their
    observations; :meth:`advance` applies the agents' actions for one step."""

    def __init__(self, scn, agents, weights: RewardWeights, terminate_on_collision: bool, log_file=None):
        self.scn, self.agents = scn, tuple(agents)
        self.terminate_on_collision = terminate_on_collision
        self.run = OpenRun(scn, log_file=log_file, make_controller=lambda ctx: AgentController(scn.params, ctx))
        self.controller: AgentController = self.run.controller
        self.weights = weights
        self.step = 0
        self.over = False
        self.obs = None
        self.result = None  # the RunResult once the episode is over
        self.last: dict[str, np.ndarray] = {}  # agent -> its latest observation

    def start(self) -> dict[str, np.ndarray]:
        run = self.run.__enter__()
        vclass = {}
        self.reward = RewardTracker(self.weights, run.scene, run.sim.step_s, vclass)
        self._vclass = vclass
        with scenario_errors(self.scn):
            while True:
                snap, self.obs, self.over = perceive(run.sim, run.stack, run.egos, run.recorder, self.step,
                                                     self.step == run.n_steps)
                ids = self.obs.ego_ids if self.obs is not None else ()
                if self.over or all(a in ids or a in run.egos.finished for a in self.agents):
                    break
                act(run.sim, run.stack, run.recorder, self.step, self.obs)
                self.step += 1
        out = self._observe(snap)
        for vid in out:
            self.reward.step(snap, vid, self._s(vid), False)
        if self.over:
            self._finish()
        return out

    def advance(self, actions: dict) -> tuple[dict, dict, dict, dict, dict]:
        """(observations, rewards, terminated, truncated, infos) of the agents driven before this step."""
        run = self.run
        live = self.driven()
        self.controller.pending = {v: np.asarray(a, float).reshape(2) for v, a in actions.items()}
        with scenario_errors(self.scn):
            act(run.sim, run.stack, run.recorder, self.step, self.obs)
            self.step += 1
            snap, self.obs, self.over = perceive(run.sim, run.stack, run.egos, run.recorder, self.step,
                                                 self.step == run.n_steps)
        obs = self._observe(snap)
        rewards, terminated, truncated, infos = {}, {}, {}, {}
        for vid in live:
            done = vid in run.egos.finished
            reached = done and vid in snap.index  # released at its goal (an ego that left is gone)
            rewards[vid], terms = self.reward.step(snap, vid, self._s(vid, snap, vid in obs), reached)
            crashed = self.terminate_on_collision and terms["new_contacts"] > 0
            terminated[vid] = done or crashed
            truncated[vid] = self.over and not terminated[vid]
            infos[vid] = {"time_s": snap.time_s, "reached_goal": reached, **terms}
            obs.setdefault(vid, self.last[vid])
        self.last.update(obs)
        if self.over:
            self._finish()
        return obs, rewards, terminated, truncated, infos

    def driven(self) -> tuple[str, ...]:
        """The agents the controller drives now."""
        ids = self.obs.ego_ids if self.obs is not None else ()
        return tuple(a for a in self.agents if a in ids)

    def _observe(self, snap) -> dict[str, np.ndarray]:
        if self.obs is None:
            return {}
        for vid, task in self.run.egos.tasks.items():
            self._vclass.setdefault(vid, task.vclass)
        x = self.controller.observe(self.obs)
        out = {v: x[k] for k, v in enumerate(self.obs.ego_ids) if v in self.agents}
        self.last.update(out)
        return out

    def _s(self, vid: str, snap=None, observed: bool = True) -> float | None:
        """The agent's arc length along its route: this step's observation's, or (the run over, the
        sensor not asked) its position's on its route frame; None once it is retired."""
        if observed:
            sc = self.controller.observer.scenes.get(vid)
            return None if sc is None else sc.s
        view = self.controller.observer.views.get(vid)
        row = snap.index.get(vid)
        return None if view is None or row is None else view.locate(snap.pos[row])[0]

    def _finish(self) -> None:
        with scenario_errors(self.scn):
            self.result = self.run.result(self.step)
        self.close()

    def trajectory(self):
        """The episode's recording so far (``trajectories.csv``'s table)."""
        return self.run.recorder.table()

    def close(self) -> None:
        self.run.__exit__(None, None, None)
