"""Road geometry on the real nets in nets/ and the polyline helpers on hand-checked toys."""
from __future__ import annotations

import pathlib

import numpy as np
import pytest

from sumo_avoid.road.polyline import (
    polyline_length,
    polyline_point_at,
    polyline_project,
)
from sumo_avoid.road.network import Road

NETS = pathlib.Path(__file__).resolve().parents[2] / "nets"


@pytest.fixture(scope="module")
def overtaking() -> Road:
    return Road.from_net_file(NETS / "overtaking.net.xml")


@pytest.fixture(scope="module")
def left_turn() -> Road:
    return Road.from_net_file(NETS / "left_turn.net.xml")


# ----------------------------------------------------------------------------- overtaking
def test_overtaking_area_is_1500_by_14(overtaking):
    assert overtaking.area.area == pytest.approx(1500.0 * 14.0, rel=0.01)
    xmin, ymin, xmax, ymax = overtaking.bounds
    assert (xmin, xmax) == pytest.approx((0.0, 1500.0), abs=0.05)
    # lanes 3.5 m wide, centres at y = -1.75 ... -12.25  ->  road spans y in [-14, 0]
    assert (ymin, ymax) == pytest.approx((-14.0, 0.0), abs=0.05)


def test_overtaking_outside_distance(overtaking):
    pts = np.array([[750.0, -7.0], [10.0, -13.9], [750.0, 20.0], [750.0, -20.0], [-3.0, -5.0], [1504.0, 3.0]])
    d = overtaking.outside_distance(pts)
    assert d.shape == (6,)
    assert d[0] == 0.0 and d[1] == 0.0
    assert d[2] == pytest.approx(20.0, abs=0.02)  # road top edge at y = 0
    assert d[3] == pytest.approx(6.0, abs=0.02)  # road bottom edge at y = -14
    assert d[4] == pytest.approx(3.0, abs=0.02)  # before the start
    assert d[5] == pytest.approx(5.0, abs=0.02)  # 3-4-5 from the corner (1500, 0)


def test_footprint_outside_distance(overtaking):
    car_in = np.array([[[10, -1], [6, -1], [6, -3], [10, -3]]], float)
    car_out = car_in + [0.0, 1.5]  # top corners at y = +0.5
    d = overtaking.footprint_outside_distance(np.concatenate([car_in, car_out]))
    assert d == pytest.approx([0.0, 0.5], abs=0.02)


def test_overtaking_solid_line_is_left_edge(overtaking):
    s = overtaking.solid_lines
    assert s.shape == (1, 2, 2)
    assert s[0] == pytest.approx(np.array([[0.0, 0.0], [1500.0, 0.0]]), abs=1e-6)
    assert len(overtaking.lane_lines("dashed")) == 3


def test_lane_centre_at(overtaking):
    assert overtaking.lane_centre_at("road", 0, 100.0) == pytest.approx([100.0, -12.25])
    assert overtaking.lane_centre_at("road", 3, 0.0) == pytest.approx([0.0, -1.75])


def test_road_is_immutable_and_cached(overtaking):
    with pytest.raises(AttributeError):
        overtaking.area = None
    assert not overtaking.boundary_segments.flags.writeable
    assert Road.from_net_file(NETS / "overtaking.net.xml") is overtaking


# ----------------------------------------------------------------------------- left turn
def test_left_turn_area_contains_junction(left_turn):
    assert left_turn.outside_distance([[0.0, 0.0], [0.0, -200.0], [-200.0, 5.0]]) == pytest.approx([0, 0, 0])
    # arms are 14 m wide (|x| <= 7): a point 10 m from the centreline of the south arm is 3 m off
    assert left_turn.outside_distance([[10.0, -100.0]])[0] == pytest.approx(3.0, abs=0.02)
    assert left_turn.bounds == pytest.approx((-250.0, -250.0, 250.0, 250.0), abs=0.05)


def test_route_path_left_turn(left_turn):
    p = left_turn.route_path(["S2C", "C2W"])
    assert p.ndim == 2 and p.shape[1] == 2
    assert 1.75 - 1e-6 <= p[0, 0] <= 5.25 + 1e-6 and p[0, 1] == pytest.approx(-250.0)
    assert p[-1, 0] == pytest.approx(-250.0)
    assert np.any((np.abs(p[:, 0]) < 11) & (np.abs(p[:, 1]) < 11))
    assert np.all(np.hypot(*np.diff(p, axis=0).T) > 1e-6)  # no duplicate consecutive points
    assert np.all(left_turn.outside_distance(p) == 0.0)  # stays on the road
    # only the leftmost lane turns left: S2C_1 (x = 1.75) -> C2W_1 (y = 1.75)
    assert p[0] == pytest.approx([1.75, -250.0])
    assert p[-1] == pytest.approx([-250.0, 1.75])


def test_route_path_lanes(left_turn):
    straight = left_turn.route_path(["S2C", "C2N"], depart_lane=0, arrival_lane=0)
    assert straight[0] == pytest.approx([5.25, -250.0]) and straight[-1] == pytest.approx([5.25, 250.0])
    assert polyline_length(straight) == pytest.approx(500.0, abs=0.01)
    # requested arrival lane differs from the connection: blend, still ends on lane 1
    change = left_turn.route_path(["S2C", "C2N"], depart_lane=0, arrival_lane=1)
    assert change[-1] == pytest.approx([1.75, 250.0])
    # depart lane without a left-turn connection: starts there, changes to lane 1 before the junction
    blended = left_turn.route_path(["S2C", "C2W"], depart_lane=0)
    assert blended[0] == pytest.approx([5.25, -250.0]) and blended[-1] == pytest.approx([-250.0, 1.75])


def test_boundary_segments_around_junction(left_turn):
    b = left_turn.boundary_segments
    assert b.ndim == 3 and b.shape[1:] == (2, 2) and len(b) > 8
    mid = b.mean(axis=1)
    near = np.all(np.abs(mid) < 12, axis=1)
    assert near.sum() >= 8  # rounded kerbs of the four corners
    # medians of the four arms are the solid lines (x = 0 or y = 0)
    s = left_turn.solid_lines
    assert len(s) == 8
    assert np.all(np.isclose(s[:, :, 0], 0.0).all(axis=1) | np.isclose(s[:, :, 1], 0.0).all(axis=1))


def test_segments_near_filters(left_turn):
    far = left_turn.segments_near([0.0, -100.0], 5.0)
    assert far.shape == (2, 2, 2)  # only the median solid lines at x = 0 (both directions)
    segs, solid = left_turn.segments_near([0.0, -100.0], 8.0, with_kind=True)
    assert solid.sum() == 2 and (~solid).sum() == 2  # plus the kerbs at x = +-7
    assert np.allclose(np.abs(segs[~solid][:, :, 0]), 7.0)
    assert left_turn.segments_near([100.0, 100.0], 20.0).shape == (0, 2, 2)
    many = left_turn.segments_near([0.0, 0.0], 20.0)
    assert len(many) > 10


# ----------------------------------------------------------------------------- polylines
L_PATH = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]])


def test_polyline_helpers_on_l_shape():
    assert polyline_length(L_PATH) == pytest.approx(15.0)
    assert polyline_point_at(L_PATH, 0.0) == pytest.approx([0, 0])
    assert polyline_point_at(L_PATH, 4.0) == pytest.approx([4, 0])
    assert polyline_point_at(L_PATH, 12.5) == pytest.approx([10, 2.5])
    assert polyline_point_at(L_PATH, -3.0) == pytest.approx([0, 0])  # clamped
    assert polyline_point_at(L_PATH, 99.0) == pytest.approx([10, 5])
    assert polyline_project(L_PATH, [4.0, -2.0]) == pytest.approx(4.0)
    assert polyline_project(L_PATH, [13.0, 3.0]) == pytest.approx(13.0)
    assert polyline_project(L_PATH, [-5.0, 1.0]) == pytest.approx(0.0)
    assert polyline_project(L_PATH, [20.0, 20.0]) == pytest.approx(15.0)
    assert polyline_project(L_PATH, [9.0, 0.5]) == pytest.approx(9.0)  # nearer the first leg
