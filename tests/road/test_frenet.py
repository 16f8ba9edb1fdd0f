"""Hand-computed checks for sumo_avoid.road.frenet (lengths m, speeds m/s, curvature 1/m)."""
import math

import numpy as np
import pytest

from sumo_avoid.road.frenet import RouteFrame


def arc(centre, radius, a0, a1, n):
    """n points on a circle arc from angle a0 to a1 (rad; a1 > a0 turns left, CCW)."""
    a = np.linspace(a0, a1, n)
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def approach_and_left_arc(radius, smooth_m=5.0):
    """Straight (-100, 0) -> (0, 0), a left quarter circle of ``radius`` (0.5 m chords), straight
    north for 100 m. The arc spans s in [100, 100 + pi R / 2]."""
    bend = arc((0.0, radius), radius, -np.pi / 2, 0.0, int(np.pi / 2 * radius / 0.5) + 1)
    north = np.array([[radius, radius + 100.0]])
    return RouteFrame.from_polyline(np.vstack([[[-100.0, 0.0]], bend, north]), smooth_m=smooth_m)


def three_lanes():
    """A lane east, an internal-lane left arc (R = 8 m, 8 points) and a lane north; the joins repeat
    their points, one of them 2 mm off (near-duplicates, as SUMO's lane shapes meet)."""
    lane1 = np.array([[0.0, 0.0], [60.0, 0.0], [100.0, 0.0]])
    internal = arc((100.0, 8.0), 8.0, -np.pi / 2, 0.0, 8)
    lane3 = np.array([[108.0, 8.002], [108.0, 40.0], [108.0, 108.0]])
    return RouteFrame.from_polyline(np.vstack([lane1, internal, lane3]))


def round_trip(frame, rng, n=1000, d_max=5.0):
    s = rng.uniform(0.0, frame.length_m, n)
    d = rng.uniform(-d_max, d_max, n)
    x = frame.to_xy(s, d)
    s2, d2 = frame.to_frenet(x)
    return s, d, x, s2, d2


# ------------------------------------------------------------------ straight line
def test_straight_line_is_the_plain_frame():
    f = RouteFrame.from_polyline([[0.0, 0.0], [100.0, 0.0]])
    s, d = f.to_frenet([[3.0, 2.0], [3.0, -2.0], [-4.0, 1.0], [107.0, -1.0]])
    assert s == pytest.approx([3.0, 3.0, -4.0, 107.0], abs=1e-12)  # before / past the ends: extrapolated
    assert d == pytest.approx([2.0, -2.0, 1.0, -1.0], abs=1e-12)  # positive left of +x, negative right
    assert f.to_xy([3.0, -4.0], [2.0, 1.0]) == pytest.approx(np.array([[3.0, 2.0], [-4.0, 1.0]]), abs=1e-12)
    assert f.length_m == 100.0
    assert f.heading_at([50.0])[0] == 0.0 and f.curvature_at([50.0])[0] == 0.0
    assert f.tangent_at([10.0])[0] == pytest.approx([1.0, 0.0]) and f.normal_at([10.0])[0] == pytest.approx([0.0, 1.0])
    assert np.all(np.isinf(f.curve_speed_limit([0.0, 50.0], np.inf)))  # straight road: no limit


def test_too_short_a_polyline_is_refused():
    with pytest.raises(ValueError):
        RouteFrame.from_polyline([[1.0, 1.0], [1.0, 1.001]])


# ------------------------------------------------------------------ circle arcs
@pytest.mark.parametrize("radius", [30.0, 60.0])
def test_curvature_of_an_arc_is_one_over_r_with_its_sign(radius):
    left = approach_and_left_arc(radius)
    mid = 100.0 + np.pi / 2 * radius * np.array([0.3, 0.5, 0.7])
    assert left.curvature_at(mid) == pytest.approx(1.0 / radius, rel=0.02)
    assert left.curvature_at([50.0, 100.0 + np.pi / 2 * radius + 50.0]) == pytest.approx([0.0, 0.0], abs=1e-9)
    right = RouteFrame.from_polyline(arc((0.0, 0.0), radius, np.pi / 2, -np.pi / 2, 200))  # clockwise
    assert right.curvature_at([right.length_m / 2])[0] == pytest.approx(-1.0 / radius, rel=0.02)
    assert left.heading_at([100.0 + np.pi / 4 * radius])[0] == pytest.approx(np.pi / 4, abs=0.01)


def test_curve_speed_limit_is_the_braking_envelope():
    # R = 30 m from s = 100 on: v_curve = sqrt(2.5 * 30) = 8.660 m/s. From s = 20 at b = 3 m/s^2
    # the curve's entry is 80 m ahead: sqrt(75 + 2 * 3 * 80) = sqrt(555) = 23.56 m/s (the smoothed
    # curvature reaches 1/30 about 1 m into the curve with smooth_m = 1: sqrt(75 + 6 * 81) = 23.69)
    f = approach_and_left_arc(30.0, smooth_m=1.0)
    v = f.curve_speed_limit([20.0, 120.0], np.inf, a_lat_max_mps2=2.5, b_comf_mps2=3.0)
    assert v[0] == pytest.approx(math.sqrt(555.0), abs=0.2)
    assert v[1] == pytest.approx(math.sqrt(75.0), rel=0.01)
    # the window is the braking distance at the current speed: 10 m/s brakes in 16.7 m, the curve
    # 80 m ahead does not matter; 30 m/s needs 150 m, and the limit binds as with the full envelope
    w = f.curve_speed_limit([20.0, 20.0], [10.0, 30.0], a_lat_max_mps2=2.5, b_comf_mps2=3.0)
    assert np.isinf(w[0]) and w[1] == pytest.approx(v[0])
    # past the curve nothing limits
    assert np.isinf(f.curve_speed_limit([200.0], np.inf)[0])


def test_max_abs_curvature_ahead_sees_the_curve_within_the_horizon():
    f = approach_and_left_arc(30.0)  # arc on s in [100, 147.1]
    got = f.max_abs_curvature_ahead([0.0, 0.0, 60.0, 120.0, 160.0], [50.0, 150.0, 45.0, 5.0, 100.0])
    assert got[0] == 0.0 and got[4] == 0.0  # [0, 50] and [160, 260] are straight (Gaussian tails end)
    assert got[1] == pytest.approx(1.0 / 30.0, rel=0.02) and got[3] == pytest.approx(1.0 / 30.0, rel=0.02)
    assert 0.0 < got[2] < 1.0 / 30.0  # [60, 105]: reaches into the curve's smoothed entry only


# ------------------------------------------------------------------ round trips
def test_round_trip_on_an_l_shaped_junction_path():
    """Two 50 m lanes meeting at 90 deg (a connection without internal lane)."""
    f = RouteFrame.from_polyline([[0.0, 0.0], [50.0, 0.0], [50.0, 50.0]])
    s, d, x, s2, d2 = round_trip(f, np.random.default_rng(1))
    assert np.abs(s2 - s).max() < 1e-3 and np.abs(d2 - d).max() < 1e-3
    assert np.abs(f.to_xy(s2, d2) - x).max() < 1e-3
    # the corner itself: its normal is the bisector, the point 2 m inside lies on it
    assert f.to_frenet([[50.0 - math.sqrt(2.0), math.sqrt(2.0)]])[0] == pytest.approx(50.0)


def test_round_trip_on_three_lanes_with_an_internal_arc():
    f = three_lanes()
    assert f.length_m == pytest.approx(100.0 + 100.0 + 2 * 8 * math.sin(np.pi / 28) * 7, abs=0.01)
    s, d, x, s2, d2 = round_trip(f, np.random.default_rng(2))
    assert np.abs(s2 - s).max() < 1e-3 and np.abs(d2 - d).max() < 1e-3
    assert np.abs(f.to_xy(s2, d2) - x).max() < 1e-3
    # and from the plane: any point within 5 m of the path maps back onto itself
    rng = np.random.default_rng(3)
    p = f.to_xy(rng.uniform(0, f.length_m, 1000), 0.0) + rng.uniform(-3.5, 3.5, (1000, 2))
    assert np.abs(f.to_xy(*f.to_frenet(p)) - p).max() < 1e-3


def test_s_hint_keeps_a_loop_on_its_branch():
    """A roundabout-like loop (radius 15 m shrinking to 12 m over 360 deg): start (15, 0) and end
    (12, 0) are 3 m apart. The point between them belongs to the start or to the end by the hint."""
    a = np.linspace(0.0, 2 * np.pi, 400)
    r = 15.0 - 3.0 * a / (2 * np.pi)
    f = RouteFrame.from_polyline(np.column_stack([r * np.cos(a), r * np.sin(a)]))
    x = np.array([[13.5, 0.2], [13.5, 0.2]])
    s, d = f.to_frenet(x, s_hint=np.array([2.0, f.length_m - 2.0]), window_m=10.0)
    # start branch: 1.5 m inside the 15 m turn, 0.2 / 13.5 rad past its start; the spiral's normal
    # leans back by atan(3 / (2 pi 15)) = 1.8 deg: s = 15 * 0.2 / 13.5 + 1.5 tan(1.8 deg) = 0.27
    assert s[0] == pytest.approx(0.27, abs=0.01) and d[0] == pytest.approx(1.5, abs=0.02)
    # end branch: 1.5 m outside the 12 m turn and just past the end (extrapolated, s > length)
    assert f.length_m < s[1] < f.length_m + 0.2 and d[1] == pytest.approx(-1.5, abs=0.02)
    assert f.to_frenet(x)[0] == pytest.approx([s[0], s[0]])  # without hints: the nearer, start branch
    assert f.to_xy(s, d) == pytest.approx(x, abs=1e-9)


# ------------------------------------------------------------------ velocities
def test_velocity_round_trip():
    f = three_lanes()
    rng = np.random.default_rng(4)
    s, d = rng.uniform(0, f.length_m, 500), rng.uniform(-3, 3, 500)
    v = rng.normal(0, 10, (500, 2))
    s_dot, d_dot = f.velocity_to_frenet(s, d, v)
    assert np.abs(f.velocity_to_xy(s, d, s_dot, d_dot) - v).max() < 1e-12
    # (1 - kappa d): on the left arc at d = +2, s_dot = |v| / (1 - 2/8) for a motion along t
    k = f.curvature_at([105.0])[0]
    s_dot, d_dot = f.velocity_to_frenet([105.0], [2.0], 6.0 * f.tangent_at([105.0]))
    assert s_dot[0] == pytest.approx(6.0 / (1.0 - 2.0 * k)) and d_dot[0] == pytest.approx(0.0, abs=1e-12)


def test_moving_along_the_arc_is_pure_s_dot():
    radius = 30.0
    a = np.linspace(0.0, np.pi, 95)  # a left half circle, 1 m chords
    f = RouteFrame.from_polyline(np.column_stack([radius * np.cos(a), radius * np.sin(a)]))
    at = a[10:-10]  # vertices lie on the circle: tangent of the circle = the frame's tangent
    pts = np.column_stack([radius * np.cos(at), radius * np.sin(at)])
    s, d = f.to_frenet(pts)
    assert d == pytest.approx(0.0, abs=1e-9)
    v = 10.0 * np.column_stack([-np.sin(at), np.cos(at)])
    s_dot, d_dot = f.velocity_to_frenet(s, d, v)
    assert s_dot == pytest.approx(10.0, abs=1e-9) and d_dot == pytest.approx(0.0, abs=1e-9)
    # at a chord's middle the frame's tangent is the chord's direction: a point moving along it
    chord = np.diff(f.vertices, axis=0)[10:-10]
    s_mid = 0.5 * (f.s_vertex[10:-11] + f.s_vertex[11:-10])
    s_dot, d_dot = f.velocity_to_frenet(s_mid, 0.0, 10.0 * chord / np.hypot(*chord.T)[:, None])
    assert s_dot == pytest.approx(10.0, abs=1e-9) and d_dot == pytest.approx(0.0, abs=1e-9)
