"""The radar obstacle map (shadow, face, cells, new-obstacle test) and the pure-pursuit tracker,
pinned to hand-computed values."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from sumo_avoid.core.types import Detections
from sumo_avoid.planning.pursuit import (
    cone_gap,
    corner_angles,
    corridor_gap,
    pursuit_velocity,
)
from sumo_avoid.planning.radar_map import RadarMap, static_returns


def test_a_return_marks_its_shadow_and_face():
    m = RadarMap(cell_m=1.0, shadow_depth_m=4.0, shadow_step_m=2.0, new_gap_m=4.0, face_half_width_m=2.0)
    assert m.add([0.0, 0.5], [[10.5, 0.5]], 1.0)  # the first return is a new obstacle
    # shadow along the line of sight (+x): 12.5, 14.5; face across it: y = -1.5 and 2.5
    assert sorted(map(tuple, m.points.tolist())) == [(10.5, -1.5), (10.5, 0.5), (10.5, 2.5), (12.5, 0.5), (14.5, 0.5)]
    assert [r[3] for r in m.rows] == [True, False, False, False, False]


def test_cells_keep_one_point_and_new_obstacles_are_far_from_earlier_returns():
    m = RadarMap(cell_m=1.0, shadow_depth_m=0.0, shadow_step_m=0.0, new_gap_m=4.0)
    assert m.add([0.0, 0.0], [[10.2, 0.2]], 0.0)
    assert not m.add([0.0, 0.0], [[10.7, 0.9]], 0.1)  # same cell: nothing added, not new
    assert len(m) == 1
    assert not m.add([0.0, 0.0], [[13.0, 0.0]], 0.2)  # 2.8 m from the first return: same obstacle
    assert len(m) == 2
    assert m.add([0.0, 0.0], [[30.0, 0.0]], 0.3)  # 17 m away: a new obstacle
    assert not m.add([0.0, 0.0], np.zeros((0, 2)), 0.4)


def test_points_keep_their_measured_range_and_refine_takes_the_closer_measurement():
    m = RadarMap(cell_m=2.0, shadow_depth_m=2.0, shadow_step_m=2.0, new_gap_m=4.0, refine=True)
    m.add([0.0, 0.5], [[40.5, 0.5]], 1.0)  # 40.5 m away; its shadow at 42.5 has the same range
    pts, rng = m.seen_since(0.0)
    assert pts == pytest.approx(np.array([[40.5, 0.5], [42.5, 0.5]])) and rng == pytest.approx([40.5, 40.5])
    m.add([30.0, 0.0], [[41.0, 1.5]], 2.0)  # the same cell measured from 11.1 m: the point moves there
    pts, rng = m.seen_since(1.5)  # (its shadow (42.98, 1.77) refines the old shadow's cell too)
    assert pts[0] == pytest.approx([41.0, 1.5]) and rng[0] == pytest.approx(math.hypot(11.0, 1.5))
    m.add([0.0, 0.0], [[40.1, 0.1]], 3.0)  # from farther again: the closer measurement stays
    assert m.seen_since(0.0)[0][0] == pytest.approx([41.0, 1.5])
    plain = RadarMap(cell_m=2.0, shadow_depth_m=0.0, shadow_step_m=0.0, new_gap_m=4.0)
    plain.add([0.0, 0.5], [[40.5, 0.5]], 1.0)
    plain.add([30.0, 0.0], [[41.0, 1.5]], 2.0)
    assert plain.points == pytest.approx(np.array([[40.5, 0.5]]))  # without refine the first point stays


def test_pursuit_aims_at_the_lookahead_point_at_the_arc_speed():
    path = np.array([[0.0, 0.0], [100.0, 0.0]])
    v = pursuit_velocity(path, 0.0, [0.0, 1.0], 0.0, cruise_mps=10.0, lookahead_m=5.0, lat_accel_mps2=2.0,
                         decel_mps2=3.0)
    # aim (5, 0) from (0, 1): direction (5, -1)/sqrt(26); sin(alpha) = 1/sqrt(26);
    # arc speed sqrt(2 * 5 / (2 / sqrt(26))) = sqrt(5 sqrt(26)) = 5.0493
    assert np.hypot(*v) == pytest.approx(math.sqrt(5 * math.sqrt(26)), rel=1e-9)
    assert v / np.hypot(*v) == pytest.approx(np.array([5.0, -1.0]) / math.sqrt(26))


def test_pursuit_steers_the_axle_the_car_turns_about():
    # a car turning about a rear axle 1.325 m behind its centre (0, 1): the axle at (-1.325, 1) aims at the point
    # 5 + 1.325 m ahead of the centre's projection, (6.325, 0): direction (7.65, -1)
    path = np.array([[0.0, 0.0], [100.0, 0.0]])
    v = pursuit_velocity(path, 0.0, [0.0, 1.0], 0.0, cruise_mps=10.0, lookahead_m=5.0, lat_accel_mps2=2.0,
                         decel_mps2=3.0, axle_m=1.325)
    assert v / np.hypot(*v) == pytest.approx(np.array([7.65, -1.0]) / math.hypot(7.65, 1.0))


def test_pursuit_brakes_for_a_corner_ahead():
    path = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]])
    assert corner_angles(path) == pytest.approx([math.pi / 2])
    v = pursuit_velocity(path, 0.0, [0.0, 0.0], 0.0, cruise_mps=20.0, lookahead_m=5.0, lat_accel_mps2=2.0,
                         decel_mps2=3.0)
    # corner radius 5 / (2 sin 45 deg) = 3.5355 m, 20 m ahead: sqrt(2 * 3.5355 + 2 * 3 * 20) = 11.273
    assert v == pytest.approx([math.sqrt(2 * 5 / (2 * math.sin(math.pi / 4)) + 120.0), 0.0])


def test_a_return_inside_an_earlier_shadow_is_remembered_as_a_return():
    m = RadarMap(cell_m=2.0, shadow_depth_m=4.0, shadow_step_m=2.0, new_gap_m=4.0)
    assert m.add([0.0, 0.0], [[10.0, 0.0]], 0.0)  # shadow at 12, 14
    assert m.add([0.0, 0.0], [[14.5, 0.5]], 0.1)  # 4.5 m from the first return: new, though in its shadow's cell
    assert not m.add([0.0, 0.0], [[14.5, 0.5]], 0.2)  # seen again: not new any more


def test_governor_gaps_ahead_of_the_front_bumper():
    pts = np.array([[10.0, 1.0], [6.0, 3.0], [-5.0, 0.0]])  # car at the origin heading +x, 4 m long
    # strip 1.5 m either side: only (10, 1): 10 - 2 = 8 m from the front; (6, 3) is 3 m off the axis
    assert corridor_gap(pts, [0.0, 0.0], 0.0, 2.0, 1.5) == pytest.approx(8.0)
    assert corridor_gap(pts, [0.0, 0.0], 0.0, 2.0, 3.5) == pytest.approx(4.0)
    assert corridor_gap(pts, [0.0, 0.0], math.pi, 2.0, 1.5) == pytest.approx(3.0)  # facing back: (-5, 0)
    # cone of 30 deg: (10, 1) at 5.7 deg, hypot(10, 1) - 2; (6, 3) at 26.6 deg, hypot(6, 3) - 2 = 4.708
    assert cone_gap(pts, [0.0, 0.0], 0.0, 2.0, math.radians(30)) == pytest.approx(math.hypot(6, 3) - 2)
    assert cone_gap(pts, [0.0, 0.0], 0.0, 2.0, math.radians(20)) == pytest.approx(math.hypot(10, 1) - 2)
    assert cone_gap(np.zeros((0, 2)), [0.0, 0.0], 0.0, 2.0, 1.0) == math.inf


def test_static_returns_leave_out_side_on_returns_on_a_road():
    """A return abeam of the ego (its line of sight 85 deg off the road) closes at ~0 m/s whether it
    stands or passes: on a road (min_cos 0.3) it is left out; straight ahead, 0 m/s is a standing
    object and 20 m/s receding is traffic."""
    rows = np.array([[20.0, 0.0, 0.0], [3.0, 85.0, 0.0], [30.0, 0.0, 20.0]])  # range, azimuth deg, radial speed
    det = Detections(0.0, ("ego",), np.zeros((1, 2)), np.zeros(1), np.zeros((1, 2)), np.zeros(3, int),
                     rows[:, 0], np.radians(rows[:, 1]), rows[:, 2])
    obs = SimpleNamespace(detections=(det,))
    pts, src = static_returns(obs, "ego", 1.0, along=0.0, min_cos=0.3)
    assert pts.tolist() == [[20.0, 0.0]] and src.tolist() == [[0.0, 0.0]]
    pts, _ = static_returns(obs, "ego", 1.0, along=0.0, min_cos=0.0)  # the arena's choice: kept
    assert np.allclose(pts, [[20.0, 0.0], [3.0 * np.cos(np.radians(85.0)), 3.0 * np.sin(np.radians(85.0))]])
