"""The rollout loop: the data flow of one step, nothing else (no feature knows it is here).

    take over departed egos -> read the snapshot (as the actuator holds it) -> record ->
    retire egos at their goal / gone -> sense -> control -> layers -> actuate -> step SUMO

``sim`` is anything with ``departed() / read() / apply(ids, pos, heading, speed) / step()``
(:class:`sumo_avoid.sumo.sim.SumoSim`, or a fake in unit tests); the plug-ins come in a
:class:`~sumo_avoid.rollout.assemble.Stack`; ``egos`` keeps who is driven and who is done
(:class:`~sumo_avoid.rollout.egos.EgoBook`). A step is two halves, :func:`perceive` (up to the
sensor) and :func:`act` (the controller on), so that a caller can step a run one step at a time
and look at the observation in between (the Gymnasium environment, :mod:`sumo_avoid.gym`).
"""
from __future__ import annotations


def perceive(sim, stack, egos, recorder, step: int, last: bool):
    """The first half of step ``step``: take over, read, record, retire, sense. Returns
    ``(snapshot, observation, over)``: observation None when no ego is driven or the run is ``over``
    (the ``last`` step, or every ego done)."""
    for vid in egos.new(sim.departed()):
        stack.add_ego(egos.take_over(sim, vid))
    snap = stack.actuator.held(sim.read())
    recorder.record(step, snap)
    for vid in egos.retire(sim, snap):
        stack.remove_ego(vid)
    if last or egos.all_done():
        return snap, None, True
    ids = egos.driven(snap)
    return snap, (stack.sensor.observe(snap, ids, stack.actuator.speeds(snap, ids)) if ids else None), False


def act(sim, stack, recorder, step: int, obs) -> None:
    """The second half: control, layers, actuate (when an ego is driven), step SUMO."""
    if obs is not None:
        command = stack.controller.act(obs)
        for layer in stack.layers:
            command = layer.filter(obs, command)
        motion = stack.actuator.step(obs, command)
        sim.apply(obs.ego_ids, motion.pos, motion.heading, motion.speed)
    recorder.record_sumo_collisions(step + 1, sim.step())


def rollout(sim, stack, egos, recorder, n_steps: int, callbacks=()) -> int:
    """Run up to ``n_steps`` steps (or until every ego is done); returns the last step index."""
    step = 0
    for step in range(n_steps + 1):
        snap, obs, over = perceive(sim, stack, egos, recorder, step, step == n_steps)
        if over:
            break
        act(sim, stack, recorder, step, obs)
        for cb in callbacks:
            cb.on_step(snap, n_steps)
    for cb in callbacks:
        cb.on_end()
    return step
