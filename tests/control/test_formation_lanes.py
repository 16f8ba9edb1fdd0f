"""The formation on a road, lane by lane (control/formation/lane_plan.py): the pure pieces pinned to
values worked out by hand, and the road case in SUMO (the diamond narrows at the two-lane closure,
breaks up into a column at the one-lane closure, with no collision and inside the carriageway)."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import SCENARIOS

from sumo_avoid.runs import outputs as evaluate
from sumo_avoid.control.formation import field as ff
from sumo_avoid.planning import formation_shape as fs
from sumo_avoid.control.formation.lane_plan import (
    assign_lanes,
    blocked_lanes,
    free_run,
    gamma_of,
    lane_units,
)
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario

ROAD = SCENARIOS / "formation" / "road_closure.toml"
LEFT = SCENARIOS / "formation" / "road_closure_left.toml"
# the road case's diamond: spacing 15 m, apex 2 atan(3.5 / 15): side slots one 3.5 m lane right and left
DIAMOND = fs.slots("diamond", 4, 15.0, 26.260)
CENTRES, WIDTHS = np.array([-3.5, 0.0, 3.5, 7.0]), np.full(4, 3.5)  # 4 lanes, bounds -5.25 .. 8.75


def test_lane_units_round_offsets_to_whole_lanes():
    assert lane_units(DIAMOND[:, 1], 3.5).tolist() == [0, -1, 1, 0]
    assert lane_units([1.74, 1.76, -5.3], 3.5).tolist() == [0, 1, -2]  # 0.497, 0.503, -1.51 lanes


def test_blocked_lanes_by_hand():
    bounds = (np.full(5, -5.25), np.full(5, 8.75))
    # leader at s = 600, rows 32.25 m deep, 80 m look-ahead: the window is [567.75, 680]
    # (s, d, length, width, speed): a stopped car in lane 0 at 650 -> blocked; a car at 25 m/s in lane 1
    # (not slower than 9 m/s) -> not; a slow car in lane 2 at 800 (rear 797.75 > 680) -> not; a truck at
    # 6 m/s in lane 3 whose front (570 + 6 = 576) is inside the window -> blocked
    obs = [[650, -3.5, 4.5, 1.8, 0.0], [640, 0.0, 4.5, 1.8, 25.0], [800, 3.5, 4.5, 1.8, 2.0], [570, 7.0, 12, 2.5, 6.0]]
    assert blocked_lanes(CENTRES, WIDTHS, bounds, obs, 600.0, 32.25, 80.0, 9.0).tolist() == [True, False, False, True]
    # a stopped car straddling lanes 1 and 2 (d = 1.75, 1.8 m wide: 0.9 m into each, > 0.3) blocks both
    assert blocked_lanes(CENTRES, WIDTHS, bounds, [[620, 1.75, 4.5, 1.8, 0.0]], 600.0, 32.25, 80.0, 9.0).tolist() \
        == [False, True, True, False]
    # a radar box of the truck in lane 3 placed from its near corner: centre d 5.75, 1.8 m wide -> 4.85 ..
    # 6.65, 0.4 m into lane 2 (> 0.3) blocks it too; with the radar's tolerance (half the box's width,
    # 0.9 m) it does not, and lane 3 (1.4 m overlap) stays blocked
    radar_truck = [[620, 5.75, 4.5, 1.8, 6.0]]
    assert blocked_lanes(CENTRES, WIDTHS, bounds, radar_truck, 600.0, 32.25, 80.0, 9.0).tolist() \
        == [False, False, True, True]
    assert blocked_lanes(CENTRES, WIDTHS, bounds, radar_truck, 600.0, 32.25, 80.0, 9.0, 0.9).tolist() \
        == [False, False, False, True]
    # the left bound drops to 5.25 somewhere in the window: lane 3 (5.25 .. 8.75) is cut by 3.5 m -> closed;
    # lo rising by 0.2 m (< 0.3) leaves lane 0 open
    shut = (np.array([-5.25, -5.05, -5.25, -5.25, -5.25]), np.array([8.75, 8.75, 5.25, 8.75, 8.75]))
    assert blocked_lanes(CENTRES, WIDTHS, shut, [], 600.0, 32.25, 80.0, 9.0).tolist() == [False, False, False, True]


def test_free_run_and_gamma_by_hand():
    assert free_run(np.array([True, True, False, False]), 1) == (2, 3)  # leader's lane blocked: the free run
    assert free_run(np.array([False, True, False, False]), 0) == (0, 0)  # the run with the leader's lane
    assert free_run(np.array([False, True, False, False]), 1) == (2, 3)  # the widest
    assert free_run(np.array([False, False, True, False]), 3) == (3, 3)
    assert free_run(np.array([True, False, True, False]), 0) == (1, 1)  # equal widths: the nearest
    assert free_run(np.array([True] * 4), 1) is None
    assert gamma_of((2, 3), 3) == (pytest.approx(2 / 3), pytest.approx(1 / 3))  # diamond over 3 lanes, 2 free
    assert gamma_of((3, 3), 3) == (pytest.approx(1 / 3), pytest.approx(1 / 3))  # one lane: gamma_min -> kappa 3
    assert gamma_of(None, 3)[0] == 0.0
    assert ff.mode(*gamma_of((0, 3), 3)) == 1 and ff.mode(*gamma_of((2, 3), 3)) == 2 and ff.mode(*gamma_of((3, 3), 3)) == 3


def test_assign_lanes_by_hand():
    u, along = lane_units(DIAMOND[:, 1], 3.5), DIAMOND[:, 0]  # [0, -1, 1, 0], [0, -15, -15, -30]
    # kappa 1, every lane free, leader in lane 1: the diamond about lane 1 (c in [0 + 1, 3 - 1] = [1, 2])
    lanes, gap = assign_lanes(u, along, 1, (0, 3), 1, 1, 15.0)
    assert lanes.tolist() == [1, 0, 2, 1] and gap.tolist() == [0, -15, -15, -30]
    # kappa 1, lane 0 blocked by a slow truck: the whole diamond one lane left (c in [2, 2])
    assert assign_lanes(u, along, 1, (1, 3), 1, 1, 15.0)[0].tolist() == [2, 1, 3, 2]
    # kappa 2, lanes 2-3 free, leader in lane 2: x = 2 + (u + 1) / 2 = 2.5, 2, 3, 2.5; the ties go to lane 2
    lanes, gap = assign_lanes(u, along, 2, (2, 3), 2, 2, 15.0)
    assert lanes.tolist() == [2, 2, 3, 2] and gap.tolist() == [0, -15, -15, -30]
    # ... leader in lane 3: the ties go to lane 3 -> f2 (-15) and f3 (-30) behind it there, 15 m apart
    lanes, gap = assign_lanes(u, along, 2, (2, 3), 3, 3, 15.0)
    assert lanes.tolist() == [3, 2, 3, 3] and gap.tolist() == [0, -15, -15, -30]
    # kappa 3, lane 3 alone: a column in slot order, 15 m apart (f1, f2 both at -15 -> -15, -30; f3 -> -45)
    lanes, gap = assign_lanes(u, along, 3, (3, 3), 2, 2, 15.0)
    assert lanes.tolist() == [3, 3, 3, 3] and gap.tolist() == [0, -15, -30, -45]


@pytest.mark.sumo
def test_road_case_narrows_then_breaks_up_into_a_column():
    """Seed 1 up to 60 s: kappa 2 before the two-lane closure (x 600 m), kappa 3 before the one-lane
    closure (x 1000 m), every member in the free lane 3 while passing it, no collision, inside the
    carriageway."""
    res = runner.run(scenario.load(ROAD, ["sim.duration_s=60", "output.plots=false"]))
    m = evaluate.run_metrics(res)
    assert m["collisions"] == 0 and m["phi_wall"] == 0.0
    log = m["formation_mode_log"]
    t = res.traj[res.traj["is_ego"]]
    lead_x = t[t["id"] == "f0"].set_index("time_s")["x"]
    first2 = next(tt for tt, k in log if k == 2)
    first3 = next(tt for tt, k in log if k == 3)
    assert lead_x.loc[round(first2, 1)] < 600.0 - 4.5 and 600.0 < lead_x.loc[round(first3, 1)] < 1000.0 - 4.5
    # passing the one-lane closure (x 1000 .. 1012): everyone in lane 3 (d > 1.75 from lane 2's centre at
    # y = -5.25: lane 3 is y in [-3.5, 0])
    beside = t[(t["x"] > 995.0) & (t["x"] < 1015.0)]
    assert len(beside) and (beside["lane"] == "m_3").all()


@pytest.mark.sumo
def test_road_case_on_radar_changes_lanes_only_into_lanes_known_free():
    """With radar the members pool their returns over V2V for the lane-change check: a front radar alone
    does not see the car alongside (before, f2 moved over within 0.11 m of bg.0 at 29 s on seed 1,
    0.06 m on seed 4). Seed 1 up to 40 s: no collision and at least 1 m to every vehicle (1.34 m
    measured)."""
    res = runner.run(scenario.load(ROAD, ["sim.duration_s=40", "output.plots=false", 'ego.sensor="radar"']))
    m = evaluate.run_metrics(res)
    assert m["collisions"] == 0 and m["min_gap_m"] > 1.0


@pytest.mark.sumo
def test_members_merge_only_where_the_car_behind_can_brake_for_them():
    """road_closure_left seed 6 (truth) up to 25 s: the formation moves two lanes left ahead of the
    truck while bg.1 comes up lane 2 at 25.7 m/s. With a gap check of 3 m + 1.5 s x closing speed, f2
    merged in front of it, slowed behind the braking leader and was rear-ended at 17.8 s; with
    Krauss's secure gap for the car behind (lane_is_free) no collision, and no member within 0.5 m of a
    vehicle."""
    res = runner.run(scenario.load(LEFT, ["sim.duration_s=25", "sim.seed=6", "output.plots=false"]))
    m = evaluate.run_metrics(res)
    assert m["collisions"] == 0 and m["sumo_collisions"] == 0 and m["min_gap_m"] > 0.5


def test_members_drive_with_the_scenarios_apf_parameters():
    """The members' road field is built with the scenario's [controllers.apf] (Context.params), its
    defaults only for a context built without a scenario."""
    from sumo_avoid.control.apf.apf import ApfParams
    from sumo_avoid.control.formation.formation import FormationParams
    from sumo_avoid.control.formation.lane_plan import LaneFormation
    from sumo_avoid.core.interfaces import Context

    mine = ApfParams(k_rep=5.0, gov_decel_mps2=3.0)
    assert LaneFormation(FormationParams(), Context(1, 0.1, params={"controllers.apf": mine})).driver.p is mine
    assert LaneFormation(FormationParams(), Context(1, 0.1)).driver.p == ApfParams()
    scn = scenario.load(ROAD, ["controllers.apf.k_rep=5.0"])
    assert scn.controller_params["apf"].k_rep == 5.0  # what the runner puts in Context.params
