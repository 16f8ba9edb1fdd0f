"""The formation on a road: the route-frame pieces (formation_road) by hand, the free gap W_max
measures, and a short run in SUMO on the 4-lane motorway (the diamond in its lanes, kappa 1 on the
free road, inside the carriageway)."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import SCENARIOS

from sumo_avoid.runs import outputs as evaluate
from sumo_avoid.control.formation import field as ff
from sumo_avoid.control.formation.road_frame import RoadFrame
from sumo_avoid.core.types import EgoTask
from sumo_avoid.road.route import LanePiece
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario

ROAD = SCENARIOS / "formation" / "road_closure.toml"


def _straight_road():
    # a straight path along +x on lane 1 of a 4-lane edge, lanes 3.5 m wide: lane centres at d = -3.5,
    # 0, 3.5, 7 -> the carriageway d in [-5.25, 8.75]
    path = np.column_stack([np.linspace(0.0, 1000.0, 101), np.zeros(101)])
    piece = LanePiece(0.0, 1000.0, "m", 1, (-3.5, 0.0, 3.5, 7.0), (-3.5, 0.0, 3.5, 7.0), (3.5,) * 4)
    return RoadFrame(EgoTask("f0", np.array([1000.0, 0.0]), path, 20.0, lanes=(piece,)))


def test_free_gap_by_hand():
    # obstacles at [-6, -2] and [3, 5] in a +-10 window: the leader's line lies in the gap [-2, 3] ->
    # W_max = 2 min(2, 3) = 4, centre +0.5; an obstacle over the line [-1, 2]: gaps [-10, -1] (9) and
    # [2, 10] (8) -> the wider, 9 wide, centre -5.5
    assert ff.free_gap([[-6.0, -2.0], [3.0, 5.0]], 10.0) == pytest.approx((-2.0, 3.0, 4.0))
    assert ff.free_gap([[-1.0, 2.0]], 10.0) == pytest.approx((-10.0, -1.0, 9.0))
    assert ff.free_width([[-1.0, 2.0]], 10.0) == 9.0


def test_road_walls_occupied_and_carrot():
    road = _straight_road()
    road.s_lead = 100.0
    # a car (4.5 x 1.8, along the road) at d = 7.5: 0.35 m from the left bound (8.75 - 7.5 - 0.9),
    # 11.85 from the right; bounds -k (gap - margin) = -0.5 (0.35 - 0.3) and -0.5 (11.85 - 0.3)
    n, b = road.walls(np.array([[100.0, 7.5]]), np.array([0.0]), np.array([4.5]), np.array([1.8]), 0.3, 0.5)
    assert n[0] == pytest.approx(np.array([[0.0, 1.0], [0.0, -1.0]]))
    assert b[0] == pytest.approx([-0.5 * 11.55, -0.5 * 0.05])
    # relative to a leader at d = 0: no room below -5.25 and above 8.75
    occ = road.occupied(0.0, 30.0, 80.0)
    assert occ[0, 1] == pytest.approx(-5.25) and occ[1, 0] == pytest.approx(8.75)
    # the carrot: 30 m ahead, across at the gap's centre; the goal itself when nearer
    assert road.carrot(np.array([100.0, 1.0]), np.array([1000.0, 0.0]), 30.0, 2.5) == pytest.approx([130.0, 3.5])
    assert road.carrot(np.array([990.0, 1.0]), np.array([1000.0, 0.0]), 30.0, 2.5) == pytest.approx([1000.0, 0.0])


def test_field_mask_only_what_is_in_the_leaders_way():
    pos, length, width = np.array([[0.0, 0.0], [-15.0, -3.5]]), np.array([4.5, 4.5]), np.array([1.8, 1.8])
    box = np.array([[-2.25, -0.9], [2.25, -0.9], [2.25, 0.9], [-2.25, 0.9]])
    polys = np.stack([box + [40.0, 0.0], box + [40.0, 3.5], box + [-40.0, 0.0]])  # ahead, next lane, behind
    m = RoadFrame.field_mask(pos, length, width, polys, np.ones((2, 3), bool), 0, 0.5)
    assert m.tolist() == [[True, False, False], [False, False, False]]


@pytest.mark.sumo
def test_road_diamond_keeps_its_lanes_on_the_free_road():
    res = runner.run(scenario.load(ROAD, ["sim.duration_s=6", "output.plots=false"]))
    m = evaluate.run_metrics(res)
    assert m["collisions"] == 0 and m["phi_wall"] == 0.0
    assert m["kappa1_share"] == 1.0 and m["formation_mode_log"] == []
    t = res.traj[res.traj["is_ego"] & (res.traj["time_s"] == 6.0)].set_index("id")
    # the diamond: f1, f2 one slot (15 m) behind the leader, a lane (3.5 m) to its right and left, f3 two
    # slots behind, each within 1 m (measured at 6 s: 0.7 m at most; from ~8 s the flow from behind
    # reaches f3, whose shield moves it aside); the leader (18 m/s, slower while the followers lag) made good
    # progress (straight road: x along, y across)
    assert t.loc["f0", "x"] - 97.75 > 6.0 * 15.0  # from its start (front bumper at 100 m) at >= 15 m/s
    for f, (dx, dy) in {"f1": (-15.0, -3.5), "f2": (-15.0, 3.5), "f3": (-30.0, 0.0)}.items():
        assert t.loc[f, "x"] - t.loc["f0", "x"] == pytest.approx(dx, abs=1.0)
        if f != "f2":
            assert t.loc[f, "y"] - t.loc["f0", "y"] == pytest.approx(dy, abs=1.0)
    # from ~3 s the shape moves one lane left (the slow truck ahead in lane 0): f2's slot is then in lane 3,
    # where bg.0 comes up at 26 m/s 33 m behind it; Krauss's secure gap for bg.0 (26 + (26^2 - 18^2) / 9 =
    # 65 m) is not there, so f2 keeps lane 2 and lets it pass (before the secure gap it cut in 15 m ahead)
    a = res.traj[res.traj["time_s"] == 6.0].set_index("id")
    assert a.loc["f2", "lane"] == "m_2" and a.loc["bg.0", "lane"] == "m_3"
    assert 0.0 < a.loc["f2", "x"] - a.loc["bg.0", "x"] < 65.0
