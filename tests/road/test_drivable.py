"""The drivable line through turns tighter than the car's turning radius (road/drivable.py): pure
maths on hand-built paths, checked against the programme's own promises (the hard radius, the
lanes where they are wide enough, zero away from the turn), plus the small helpers pinned by hand."""
import numpy as np
import pytest

from sumo_avoid.road.drivable import (
    HARD_FACTOR,
    REACH_M,
    DrivableLine,
    drivable_line,
    tight_stretches,
)
from sumo_avoid.road.frenet import RouteFrame

R_MIN = 4.25


def _turn(r: float, angle_deg: float = 90.0, leg_m: float = 40.0) -> np.ndarray:
    """Straight east, a left arc of radius r drawn with ~0.25 m chords (as SUMO draws internal
    lanes), straight on: (P, 2)."""
    a = np.radians(angle_deg)
    leg1 = np.column_stack([np.linspace(-leg_m, 0.0, 161), np.zeros(161)])
    th = np.linspace(0.0, a, max(int(r * a / 0.25), 4) + 1)
    arc = np.column_stack([r * np.sin(th), r - r * np.cos(th)])
    u = np.array([np.cos(a), np.sin(a)])
    leg2 = arc[-1] + np.linspace(0.0, leg_m, 161)[:, None] * u
    return np.vstack([leg1, arc[1:], leg2[1:]])


def _const(lo, hi):
    return lambda s: (np.full(len(np.atleast_1d(s)), lo), np.full(len(np.atleast_1d(s)), hi))


def _three_point_curvature(x: np.ndarray) -> np.ndarray:
    a, b, c = x[:-2], x[1:-1], x[2:]
    ab, bc, ca = (np.hypot(*(q).T) for q in (b - a, c - b, a - c))
    cross = (b - a)[:, 0] * (c - b)[:, 1] - (b - a)[:, 1] * (c - b)[:, 0]
    return 2.0 * cross / (ab * bc * ca)


def test_offset_and_slope_interpolate_the_grid():
    line = DrivableLine(np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 0.0]))
    assert line.offset([0.5, 1.0, 1.5, -3.0, 9.0]).tolist() == [0.5, 1.0, 0.5, 0.0, 0.0]
    assert line.slope([0.5, 1.5, -3.0, 9.0]).tolist() == [1.0, -1.0, 0.0, 0.0]
    assert line.max_abs_m == 1.0


def test_tight_stretches_are_widened_by_the_reach_and_merged():
    s = np.arange(0.0, 20.0, 0.5)  # 40 nodes
    k = np.zeros(40)
    k[[10, 11, 30]] = 0.5
    assert tight_stretches(s, k, 0.2, 2.0) == [(6, 15), (26, 34)]  # 2 m = 4 nodes either side
    assert tight_stretches(s, k, 0.2, 5.0) == [(0, 39)]  # 10 nodes: the two overlap
    assert tight_stretches(s, k, 0.6, 2.0) == []


@pytest.mark.parametrize("path", [np.array([[0.0, 0.0], [200.0, 0.0]]), _turn(30.0)])
def test_a_path_the_car_can_drive_gets_no_line(path):
    frame = RouteFrame.from_polyline(path)
    assert drivable_line(frame, _const(-1.6, 1.6), 0.9, R_MIN).s.size == 0
    assert drivable_line(frame, _const(-1.6, 1.6), 0.9, 0.0).s.size == 0  # no radius: no limit


def test_a_turn_tighter_than_the_car_gets_a_line_it_can_drive():
    frame = RouteFrame.from_polyline(_turn(3.0))
    line = drivable_line(frame, _const(-5.0, 5.0), 0.9, R_MIN, max_shift_m=5.0)
    x = frame.to_xy(line.s, line.d)
    k_line = np.abs(_three_point_curvature(x)).max()
    k_path = np.abs(_three_point_curvature(frame.to_xy(line.s, np.zeros(len(line.s))))).max()
    assert k_path > 0.3  # the lane: radius 3 m
    assert k_line <= 1.0 / (HARD_FACTOR * R_MIN) * 1.02  # the line: >= 1.1 R_min (to 2 %)
    # a left turn is cut on the inside (d > 0 at the arc's middle) and the line is 0 away from it
    mid = 40.0 + 3.0 * np.pi / 4
    assert line.offset(mid)[0] > 0.5
    far = (line.s < 40.0 - REACH_M - 1.0) | (line.s > 40.0 + 3.0 * np.pi / 2 + REACH_M + 1.0)
    assert np.all(line.d[far] == 0.0)


def test_the_line_keeps_to_the_lanes_where_they_are_wide_enough():
    frame = RouteFrame.from_polyline(_turn(4.0))
    lo, hi, half = -2.4, 2.4, 0.9
    line = drivable_line(frame, _const(lo, hi), half, R_MIN)
    assert line.s.size > 0
    # inside the lanes narrowed by half the width and the 0.1 m margin (solver tolerance 1e-6)
    assert np.all(line.d <= hi - half - 0.1 + 1e-6) and np.all(line.d >= lo + half + 0.1 - 1e-6)
    assert np.abs(_three_point_curvature(frame.to_xy(line.s, line.d))).max() <= 1.0 / (HARD_FACTOR * R_MIN) * 1.02
