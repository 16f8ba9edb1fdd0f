"""Formation maths (SPEC §3): shapes, F_re1 / F_re2, the alpha/beta reshaping, W, W_max, gamma,
gamma_min and kappa, each against values computed by hand."""
from __future__ import annotations

import math

import numpy as np
import pytest

from sumo_avoid.control import CONTROLLERS
from sumo_avoid.control.formation import field as ff
from sumo_avoid.control.formation.formation import FormationController, FormationParams, forward_cone
from sumo_avoid.control.formation.trail import LeaderTrail
from sumo_avoid.planning import formation_shape as fs
from sumo_avoid.planning.formation_shape import member_order


def test_registered_and_seed_triangle():
    assert CONTROLLERS["formation"].factory is FormationController
    # the seed's triangle of 6: (0,0), (-1,-1), (-1,1), (-2,-2), (-2,2), (-2,0) in its unit (x 8 m)
    got = fs.slots("triangle", 6, 8.0, 90.0)
    assert got == pytest.approx(8.0 * np.array([[0, 0], [-1, -1], [-1, 1], [-2, -2], [-2, 2], [-2, 0]]), abs=1e-9)
    # apex 60 deg: half angle 30 deg, row 1 at +-tan(30) s = +-0.57735 s
    assert fs.slots("triangle", 3, 10.0, 60.0)[1:] == pytest.approx(np.array([[-10.0, -5.773503], [-10.0, 5.773503]]), abs=1e-6)


def test_other_shapes():
    assert fs.slots("line", 4, 5.0).tolist() == [[0, 0], [0, -5], [0, 5], [0, -10]]
    assert fs.slots("column", 3, 5.0).tolist() == [[0, 0], [-5, 0], [-10, 0]]
    assert fs.slots("v", 5, 2.0) == pytest.approx(np.array([[0, 0], [-2, -2], [-2, 2], [-4, -4], [-4, 4]]))
    assert fs.slots("diamond", 6, 1.0) == pytest.approx(np.array([[0, 0], [-1, -1], [-1, 1], [-2, 0], [-3, -1], [-3, 1]]))
    # the road case's diamond: 15 m along, apex 2 atan(3.5 / 15): one 3.5 m lane to each side
    apex = 2.0 * math.degrees(math.atan(3.5 / 15.0))
    assert fs.slots("diamond", 4, 15.0, apex) == pytest.approx(np.array([[0, 0], [-15, -3.5], [-15, 3.5], [-30, 0]]))
    with pytest.raises(ValueError):
        fs.slots("circle", 3, 1.0)


def test_to_world_turns_and_scales():
    off = np.array([[-8.0, 8.0]])
    # heading 90 deg: forward is +y, left is -x; lateral scale 0.5 -> (-8, 4) -> (-4, -8) + origin
    assert fs.to_world(off, [10.0, 20.0], math.pi / 2, 0.5) == pytest.approx(np.array([[6.0, 12.0]]))


def test_min_lateral_scale_triangle():
    # rows 8 m apart (> 4 + 1): only row 2's neighbours (dy = 16) count: (1.8 + 1) / 16
    assert ff.min_lateral_scale(fs.slots("triangle", 6, 8.0), 4.0, 1.8, 1.0) == pytest.approx(0.175)
    assert ff.min_lateral_scale(fs.slots("column", 3, 8.0), 4.0, 1.8, 1.0) == 0.0
    assert ff.min_lateral_scale(fs.slots("line", 3, 2.0), 4.0, 1.8, 1.0) == 1.0  # capped at 1


def test_repulsion_terms_by_hand():
    # rho = 2, rho0 = 4, rho_g = 9, n = 2, eta_re = 3: k = 1/2 - 1/4 = 0.25
    # F_re1 = 3 * 0.25 * 81 / 4 = 15.1875 ; F_re2 = (2/2) * 3 * 0.0625 * 9 = 1.6875
    f1, f2 = ff.repulsion_terms([2.0], [[0.0, 1.0]], [9.0], [[1.0, 0.0]], 3.0, 4.0, 2.0)
    assert f1 == pytest.approx(np.array([[0.0, 15.1875]]))
    assert f2 == pytest.approx(np.array([[1.6875, 0.0]]))
    # n = 1: F_re1 = eta k rho_g / rho^2 = 3 * 0.25 * 9 / 4 = 1.6875 ; F_re2 = 0.5 * 3 * 0.0625 = 0.09375
    f1, f2 = ff.repulsion_terms([2.0], [[1.0, 0.0]], [9.0], [[0.0, -1.0]], 3.0, 4.0, 1.0)
    assert f1 == pytest.approx(np.array([[1.6875, 0.0]])) and f2 == pytest.approx(np.array([[0.0, -0.09375]]))
    # beyond rho0 nothing; at the goal (rho_g = 0) nothing
    f1, f2 = ff.repulsion_terms([5.0, 2.0], [[1.0, 0.0]] * 2, [9.0, 0.0], [[0.0, 1.0]] * 2, 3.0, 4.0, 2.0)
    assert np.abs(f1).sum() == 0 and np.abs(f2).sum() == 0


def test_attraction():
    assert ff.attraction([[1.0, 1.0]], [4.0, 5.0], 0.5) == pytest.approx(np.array([[1.5, 2.0]]))


def test_reshape_by_hand():
    # heading 0: p = x, q = y. F = (-3, 4), |F| = 5; alpha = -0.5, beta = 0.2:
    # p' = 0.5 * -3 = -1.5 ; q' = 4 + 0.2 * 5 = 5
    assert ff.reshape([[-3.0, 4.0]], [0.0], -0.5, 0.2) == pytest.approx(np.array([[-1.5, 5.0]]))
    # heading 90 deg: p along +y, q along -x. F = (0, -2) (head-on push back): p = -2, q = 0
    # p' = (1 - 0.3) * -2 = -1.4 ; q' = 0 + 0.3 * 2 = 0.6 -> world (-0.6, -1.4)
    assert ff.reshape([[0.0, -2.0]], [math.pi / 2], -0.3, 0.3) == pytest.approx(np.array([[-0.6, -1.4]]))


def test_widths_gamma_and_mode():
    assert ff.formation_width(np.array([-16.0, 0.0, 16.0]), 1.8) == pytest.approx(33.8)
    # y = 0 free between -3 and 5: W_max = 2 min(3, 5) = 6 (centred on the leader's line)
    assert ff.free_width([[-9.0, -3.0], [5.0, 7.0]], 20.0) == pytest.approx(6.0)
    # nothing ahead: the whole window
    assert ff.free_width(np.zeros((0, 2)), 12.0) == 24.0
    # y = 0 blocked by [-1, 2]: gaps [-20, -1] (19) and [2, 4] (2): the wider, 19
    assert ff.free_width([[-1.0, 2.0], [4.0, 30.0]], 20.0) == pytest.approx(19.0)
    # overlapping obstacles merge: [-2, 1] u [0.5, 3] = [-2, 3]; gaps 18 and 17
    assert ff.free_width([[-2.0, 1.0], [0.5, 3.0]], 20.0) == pytest.approx(18.0)
    # gamma_min of the triangle of 6: (0.175 * 32 + 1.8 + 2 * 1) / 33.8 = 9.4 / 33.8
    assert ff.gamma_min(0.175, 32.0, 1.8, 1.0, 33.8) == pytest.approx(9.4 / 33.8)
    assert ff.lateral_scale(20.0, 32.0, 1.8, 1.0) == pytest.approx((20.0 - 2.0 - 1.8) / 32.0)
    assert ff.lateral_scale(50.0, 32.0, 1.8, 1.0) == 1.0
    assert [ff.mode(g, 0.3) for g in (1.2, 1.0, 0.99, 0.31, 0.3, 0.1)] == [1, 1, 2, 2, 3, 3]


def test_params_validation_and_order():
    with pytest.raises(ValueError):
        FormationParams(alpha=1.0)
    with pytest.raises(ValueError):
        FormationParams(shape="blob")
    assert member_order(FormationParams(), ["f10", "f2", "f0", "f1"]) == ["f0", "f1", "f2", "f10"]
    assert member_order(FormationParams(members=("b", "a")), ["a", "b"]) == ["b", "a"]


def test_forward_cone():
    # a command 120 deg left of the heading is turned to heading + 75 deg, same speed
    v = forward_cone(2.0 * np.array([math.cos(2.0944), math.sin(2.0944)]), 0.0, math.radians(75))
    assert v == pytest.approx(2.0 * np.array([math.cos(math.radians(75)), math.sin(math.radians(75))]), abs=1e-9)
    assert forward_cone(np.array([1.0, 0.5]), 0.0, math.radians(75)) == pytest.approx([1.0, 0.5])


def test_bridges_close_only_gaps_too_narrow_to_pass():
    # unit squares at x 0-1 and x 4-5 (3 m apart) and one at y 10-11: with a passage of 3.5 m the first
    # two are joined by their hull, the rectangle [0, 5] x [0, 1]; at 3.0 m nothing is (3 m passes)
    a = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    polys = np.stack([a, a + [4.0, 0.0], a + [0.0, 10.0]])
    hulls, pairs = ff.bridges(polys, 3.5)
    assert pairs.tolist() == [[0, 1]]
    assert sorted(map(tuple, hulls[0].tolist())) == [(0.0, 0.0), (0.0, 1.0), (5.0, 0.0), (5.0, 1.0)]
    assert len(ff.bridges(polys, 3.0)[0]) == 0 and len(ff.bridges(polys[:1], 9.0)[0]) == 0
    with pytest.raises(ValueError):
        FormationParams(shield_members="box")


def test_lost_follower_follows_the_leaders_path_then_its_goal():
    """Once the leader is done, a follower that made < 1 m towards its goal in 10 s aims at the point
    spacing_m (8 m) ahead on the leader's path past its nearest point, never going back along it, and
    at its own goal for good once that point would lie beyond the path's end (by hand: a path along
    the x axis from 0 to 100 m)."""
    c = LeaderTrail(FormationParams())
    x = np.arange(0.0, 100.01, 0.5)
    c.path = np.column_stack([x, np.zeros_like(x), x])
    goal = np.array([[0.0, 50.0]])
    at = np.array([[50.0, 5.0]])
    for k in range(100):  # 9.9 s without progress: still its goal
        assert c.lost_goals(["f1"], at, goal, 0.1 * k).tolist() == goal.tolist()
    # at 10 s: lost -> the path's point 50 + 8 = 58 m
    assert c.lost_goals(["f1"], at, goal, 10.0) == pytest.approx(np.array([[58.0, 0.0]]))
    # it drifted back beside x = 40: still 58 (never back along the path); at x = 70: 78
    assert c.lost_goals(["f1"], np.array([[40.0, 3.0]]), goal, 10.1) == pytest.approx(np.array([[58.0, 0.0]]))
    assert c.lost_goals(["f1"], np.array([[70.0, 1.0]]), goal, 10.2) == pytest.approx(np.array([[78.0, 0.0]]))
    # at x = 93: 93 + 8 > 100 -> its goal, and so from then on wherever it is
    assert c.lost_goals(["f1"], np.array([[93.0, 0.0]]), goal, 10.3).tolist() == goal.tolist()
    assert c.lost_goals(["f1"], np.array([[50.0, 5.0]]), goal, 30.0).tolist() == goal.tolist()
