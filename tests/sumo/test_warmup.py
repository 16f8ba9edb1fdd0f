"""Before its first ego departs a run reads only the signals (``SumoSim.world_before_egos`` False: the recording
keeps the road users near egos, so nothing read then is used), and records exactly what reading the whole world
would have recorded. On the streets library's van (real SUMO): the ego departs at 15 s; cars, cyclists and the
van are on the street from the start."""
from __future__ import annotations

from conftest import SCENARIOS

from sumo_avoid.rollout.loop import rollout
from sumo_avoid.runs.runner import OpenRun
from sumo_avoid.scenario import spec as scenario


def _run(whole_world: bool):
    scn = scenario.load(SCENARIOS / "streets" / "van_bike_lane.toml", ["output.plots=false", "sim.duration_s=20"])
    with OpenRun(scn) as r:
        assert r.sim.world_before_egos is False  # the scenario records near its egos (record_radius_m 300)
        r.sim.world_before_egos = whole_world
        for _ in range(50):  # 5 s: traffic on the street, the ego not yet departed
            r.sim.step()
        before = r.sim.read()
        steps = rollout(r.sim, r.stack, r.egos, r.recorder, r.n_steps - 50)
        return before, r.result(steps)


def test_the_world_is_read_once_an_ego_is_there_and_recorded_the_same():
    whole_before, whole = _run(True)
    quiet_before, quiet = _run(False)
    assert whole_before.n > 0 and quiet_before.n == 0  # cars and the van are there; only the signals were read
    assert quiet_before.signals == whole_before.signals
    assert (whole.traj["id"] == "ego").any()  # the ego departed and drove
    assert quiet.traj.equals(whole.traj) and quiet.persons.equals(whole.persons)
    assert quiet.signals.equals(whole.signals)
