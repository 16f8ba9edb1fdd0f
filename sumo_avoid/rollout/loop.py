"""The rollout loop: the data flow of one step, nothing else (no feature knows it is here).

    take over departed egos -> read the snapshot (as the actuator holds it) -> record ->
    retire egos at their goal / gone -> sense -> control -> layers -> actuate -> step SUMO

``sim`` is anything with ``departed() / read() / apply(ids, pos, heading, speed) / step()``
(:class:`sumo_avoid.sumo.sim.SumoSim`, or a fake in unit tests); the plug-ins come in a
:class:`~sumo_avoid.rollout.assemble.Stack`; ``egos`` keeps who is driven and who is done
(:class:`~sumo_avoid.rollout.egos.EgoBook`).
"""
from __future__ import annotations


def rollout(sim, stack, egos, recorder, n_steps: int, callbacks=()) -> int:
    """Run up to ``n_steps`` steps (or until every ego is done); returns the last step index."""
    step = 0
    for step in range(n_steps + 1):
        for vid in egos.new(sim.departed()):
            stack.add_ego(egos.take_over(sim, vid))
        snap = stack.actuator.held(sim.read())
        recorder.record(step, snap)
        for vid in egos.retire(sim, snap):
            stack.remove_ego(vid)
        if step == n_steps or egos.all_done():
            break
        ids = egos.driven(snap)
        if ids:
            obs = stack.sensor.observe(snap, ids, stack.actuator.speeds(snap, ids))
            command = stack.controller.act(obs)
            for layer in stack.layers:
                command = layer.filter(obs, command)
            motion = stack.actuator.step(obs, command)
            sim.apply(ids, motion.pos, motion.heading, motion.speed)
        recorder.record_sumo_collisions(step + 1, sim.step())
        for cb in callbacks:
            cb.on_step(snap, n_steps)
    for cb in callbacks:
        cb.on_end()
    return step
