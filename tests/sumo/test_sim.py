"""The libsumo boundary on a real net: snapshot conversion (front bumper -> centre, compass ->
math heading), immutability, and an ego placed exactly by moveToXY."""
import math

import numpy as np
import pytest
from conftest import ROOT, SCENARIOS

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.sumo.sim import SumoSim, sumo_args


def _start():
    args = sumo_args(ROOT / "nets" / "overtaking.net.xml", [SCENARIOS / "crash_straight.rou.xml"], [], 0.1, 1, 0.8,
                     None)
    return SumoSim(args)


def test_snapshot_centres_headings_and_sizes():
    with _start() as sim:
        sim.step()
        snap = sim.read()
        i, j = snap.index["ego"], snap.index["parked"]
        # departPos is the front bumper: ego inserted with its front at x = 20 in the first step,
        # centre 4.5/2 = 2.25 m behind; lane 1 centre at y = -8.75; heading east = 0 rad
        assert snap.pos[i] == pytest.approx([20.0 - 2.25, -8.75])
        assert snap.pos[j] == pytest.approx([80.0 - 2.25, -8.75])
        assert snap.heading[i] == pytest.approx(0.0)
        assert snap.length[i] == 4.5 and snap.width[i] == 1.8
        assert snap.vel[i] == pytest.approx([10.0, 0.0])
        assert not snap.is_ego.any()  # nobody taken over yet


def test_snapshot_is_immutable():
    snap = Snapshot(0.0, ("a",), [[1.0, 2.0]], [[0.0, 0.0]], [0.0], [4.5], [1.8], [True])
    with pytest.raises(ValueError):
        snap.pos[0, 0] = 5.0
    with pytest.raises(AttributeError):
        snap.time_s = 3.0


def test_ego_is_placed_exactly_and_off_lane():
    with _start() as sim:
        sim.step()
        sim.take_over("ego")
        # centre 3 m left of the lane centre, heading 30 degrees: off the lane grid entirely
        h = math.radians(30.0)
        sim.apply(["ego"], np.array([[40.0, -5.75]]), np.array([h]), np.array([5.0]))
        sim.step()
        snap = sim.read()
        i = snap.index["ego"]
        assert snap.pos[i] == pytest.approx([40.0, -5.75], abs=1e-6)
        assert snap.heading[i] == pytest.approx(h, abs=1e-9)
        assert snap.is_ego[i]


def test_an_ego_released_at_its_goal_is_gone_and_the_others_step_on():
    """libsumo keeps the subscription of a removed vehicle: without dropping it first, the next step
    failed with "Vehicle 'parked' is not known" (two egos, one done before the other)."""
    with _start() as sim:
        sim.step()
        sim.take_over("ego")
        sim.take_over("parked")
        sim.release("parked")
        for _ in range(3):
            sim.step()
        assert sim.read().ids == ("ego",)


def test_a_road_user_sumo_gives_no_finite_position_is_left_out_of_that_step(monkeypatch):
    """SUMO gave a person on a walking area a NaN position for one step (an unseen Sao Paulo district with
    randomTrips people: the run crashed in the recorder's neighbour search). The snapshot leaves such a
    person or vehicle out of that step, notes it once, and keeps every other road user as SUMO gave it."""
    import libsumo

    args = sumo_args(SCENARIOS / "streets" / "zebra.net.xml", [SCENARIOS / "streets" / "zebra.rou.xml"], [], 0.1, 1,
                     0.8, None)
    with SumoSim(args) as sim:
        for _ in range(300):
            sim.step()
        before = sim.read()
        people = [v for v, p in zip(before.ids, before.is_person) if p]
        cars = [v for v, p in zip(before.ids, before.is_person) if not p]
        assert len(people) >= 2 and len(cars) >= 2
        c = libsumo.constants
        real_p, real_v = libsumo.person.getAllSubscriptionResults, libsumo.vehicle.getAllSubscriptionResults

        def nan_pose(real, who):
            def results():
                res = {k: dict(v) for k, v in real().items()}
                res[who][c.VAR_POSITION3D] = (math.nan, math.nan, 0.0)
                res[who][c.VAR_ANGLE] = math.nan
                return res
            return results

        monkeypatch.setattr(libsumo.person, "getAllSubscriptionResults", nan_pose(real_p, people[0]))
        monkeypatch.setattr(libsumo.vehicle, "getAllSubscriptionResults", nan_pose(real_v, cars[0]))
        snap = sim.read()
        assert people[0] not in snap.ids and cars[0] not in snap.ids
        assert set(snap.ids) == set(before.ids) - {people[0], cars[0]}
        assert np.isfinite(snap.pos).all() and np.isfinite(snap.heading).all()
        for k, v in enumerate(snap.ids):  # the others as SUMO gives them
            assert snap.pos[k] == pytest.approx(before.pos[before.index[v]])
        assert sim._no_pose == {people[0], cars[0]}


def test_a_previous_simulations_signals_do_not_leak_into_the_next_ones_first_snapshot():
    # libsumo keeps the last run's subscription results until the next run's first step: a replay of the
    # overtaking run (no signals) once failed on a signal of the grid run before it in the same test process
    grid = ROOT / "scenarios" / "roads"
    with SumoSim(sumo_args(grid / "grid_static.net.xml", [grid / "grid_static.rou.xml"], [], 0.1, 1, 0.8, None)) as sim:
        for _ in range(3):
            sim.step()
        assert sim.read().signals  # the grid's six signals
    with _start() as sim:
        assert sim.read().signals == {}
        sim.step()
        assert sim.read().signals == {}
