"""The GA planner's road frame (sumo_avoid/planning/corridor.py), pinned to hand-computed values."""
import numpy as np
import pytest

from sumo_avoid.road.route import LanePiece
from sumo_avoid.planning.corridor import (
    all_lanes_corridor,
    corridor_clip,
    follow_speed,
    meeting_points,
    pick_lane,
    wall_points,
    whole_lanes,
)

# three lanes of 3.5 m, centres at d = 0, 3.5, 7 (a straight edge of 100 m, then a junction, then 100 m)
PIECES = (LanePiece(0.0, 100.0, "a", 0, (0.0, 3.5, 7.0), (0.0, 3.5, 7.0), (3.5, 3.5, 3.5)),
          LanePiece(100.0, 110.0, ":j_0", 0, (0.0,), (0.0,), (3.5,)),
          LanePiece(110.0, 210.0, "b", 0, (0.0, 3.5, 7.0), (0.0, 3.5, 7.0), (3.5, 3.5, 3.5)))


def test_all_lanes_corridor_spans_every_lane_and_bridges_the_junction():
    lo, hi = all_lanes_corridor(PIECES)(np.array([50.0, 105.0, 150.0]))
    assert lo == pytest.approx([-1.75] * 3) and hi == pytest.approx([8.75] * 3)  # no taper, no narrowing


def test_the_corridor_and_lane_centres_leave_out_lanes_the_ego_may_not_use():
    # lane 0 a bike lane (1.5 m, centre d -2.5), lane 1 the car lane (centre 0), lane 2 a bus lane
    # (centre 3.5): a car's planner walls span the car lane alone (-1.75 .. 1.75); its own lane is
    # always usable (LanePiece.usable)
    from sumo_avoid.planning.corridor import lane_centres

    pieces = (LanePiece(0.0, 100.0, "a", 1, (-2.5, 0.0, 3.5), (-2.5, 0.0, 3.5), (1.5, 3.5, 3.5), (False, True, False)),)
    lo, hi = all_lanes_corridor(pieces)(np.array([0.0, 50.0, 100.0]))
    assert lo == pytest.approx([-1.75] * 3) and hi == pytest.approx([1.75] * 3)
    assert lane_centres(pieces, 50.0, usable_only=True) == pytest.approx([0.0])
    assert lane_centres(pieces, 50.0) == pytest.approx([-2.5, 0.0, 3.5])


def test_meeting_points_of_a_slower_car_ahead():
    # ego at s 0 planned at 10 m/s, car 20 m ahead in the next lane at 5 m/s, both 4.5 m long:
    # G = 4.5 + 6 = 10.5; |20 - 5 t| < 10.5 for t in (1.9, 6.1): the ego covers s 19 .. 61
    pts = meeting_points([[20.0, 3.5]], [[5.0, 0.0]], [4.5], [1.8], 0.0, 0.0, 10.0, 4.5, 6.0, 100.0, 1.0, 1.5)
    assert pts[:, 0].min() == pytest.approx(19.0) and pts[:, 0].max() == pytest.approx(61.0)
    assert sorted(set(np.round(pts[:, 1], 6))) == pytest.approx([2.6, 3.5, 4.4])
    # headway 1 s x closing speed 5 m/s: G = 15.5, t in (0.9, 7.1): s 9 .. 71
    pts = meeting_points([[20.0, 3.5]], [[5.0, 0.0]], [4.5], [1.8], 0.0, 0.0, 10.0, 4.5, 6.0, 100.0, 1.0, 1.5, 1.0)
    assert pts[:, 0].min() == pytest.approx(9.0) and pts[:, 0].max() == pytest.approx(71.0)


def test_meeting_points_leave_out_what_never_meets_and_followers_in_the_own_lane():
    args = ([4.5], [1.8], 0.0, 0.0, 10.0, 4.5, 6.0, 100.0, 1.0, 1.5)
    assert len(meeting_points([[30.0, 3.5]], [[15.0, 0.0]], *args)) == 0  # ahead and pulling away
    assert len(meeting_points([[-20.0, 0.0]], [[15.0, 0.0]], *args)) == 0  # behind in the ego's lane
    # the same car behind in the next lane comes alongside: |-20 + 5 t| < 10.5 for t in (1.9, 6.1)
    pts = meeting_points([[-20.0, 3.5]], [[15.0, 0.0]], *args)
    assert pts[:, 0].min() == pytest.approx(19.0) and pts[:, 0].max() == pytest.approx(61.0)


def test_pick_lane_nearest_free_lane_centre():
    centres = [7.0, 0.0, 3.5]
    assert pick_lane(centres, 0.2, 60.0, np.zeros((0, 2)), 3.0) == 0.0
    assert pick_lane(centres, 0.2, 60.0, [[60.0, 0.0]], 3.0) == 3.5  # own lane blocked: the next one
    assert pick_lane(centres, 5.25, 60.0, [[60.0, 0.0]], 3.0) == 3.5  # a tie (1.75 each): the right one
    # nothing free: the most clearance (points 1 m off each centre but the left one's 2 m)
    assert pick_lane(centres, 0.0, 60.0, [[60.0, 1.0], [60.0, 4.5], [60.0, 9.0]], 3.0) == 7.0


def test_whole_lanes_blocks_the_lane_or_the_line_within_the_measurement_error():
    # measured at 30 m: tolerance 0.2 + 0.0175 * 30 = 0.725 m
    out = whole_lanes([[30.0, 3.0]], [30.0], PIECES, 0.0, 0.2, 0.0175)  # 1.25 m inside its lane
    assert out == pytest.approx(np.array([[30.0, 1.75], [30.0, 3.5], [30.0, 5.25]]))
    out = whole_lanes([[30.0, 5.0]], [30.0], PIECES, 0.0, 0.2, 0.0175)  # 0.25 m from the line: on the line
    assert out == pytest.approx(np.array([[30.0, 5.25]]))
    out = whole_lanes([[30.0, 5.64]], [30.0], PIECES, 0.0, 0.2, 0.0175)  # 0.39 m into the left lane: the line
    assert out == pytest.approx(np.array([[30.0, 5.25]]))
    # the same point measured at 10 m (tolerance 0.375 m) is 1.36 m inside the left lane: blocks it
    out = whole_lanes([[30.0, 5.64]], [10.0], PIECES, 0.0, 0.2, 0.0175)
    assert out == pytest.approx(np.array([[30.0, 5.25], [30.0, 7.0], [30.0, 8.75]]))
    # the error is that of the measurement, not of the ego's distance now: measured at 70 m
    # (tolerance 1.425 m), 0.39 m from the line stays on the line with the ego 5 m away
    out = whole_lanes([[30.0, 5.64]], [70.0], PIECES, 25.0, 0.2, 0.0175)
    assert out == pytest.approx(np.array([[30.0, 5.25]]))


def test_whole_lanes_body_lies_along_the_lane_away_from_the_ego():
    # 4 m deep, a point every 2 m: s + 0, 2, 4 ahead of the ego; s - 0, 2, 4 behind it
    out = whole_lanes([[30.0, 5.0], [-20.0, 5.0]], [30.0, 20.0], PIECES, 0.0, 0.2, 0.0175, 4.0, 2.0)
    assert out == pytest.approx(np.array([[30.0, 5.25], [32.0, 5.25], [34.0, 5.25],
                                          [-20.0, 5.25], [-22.0, 5.25], [-24.0, 5.25]]))


def test_corridor_clip_sorts_and_keeps_waypoints_inside():
    clip = corridor_clip(all_lanes_corridor(PIECES), 1.8, 10.0, 70.0)
    pop = np.array([[[10.0, 0.0], [40.0, 12.0], [20.0, -5.0], [90.0, 3.0], [70.0, 3.5]]])
    out = clip(pop)
    assert out[0] == pytest.approx(np.array([[10.0, 0.0], [20.0, 0.05], [40.0, 6.95], [70.0, 3.0], [70.0, 3.5]]))


def test_wall_points_moved_out():
    w = wall_points(all_lanes_corridor(PIECES), 0.0, 4.0, 2.0, 0.5)
    assert w == pytest.approx(np.array([[0, -2.25], [2, -2.25], [4, -2.25], [0, 9.25], [2, 9.25], [4, 9.25]]))


def test_follow_speed_stops_behind_a_vehicle_in_the_strip():
    # gap = 30 - 0 - 4.5 = 25.5 m, minus 3 m standstill: sqrt(2 * 3 * 22.5) = sqrt(135)
    v = follow_speed([[30.0, 0.5], [10.0, 3.5]], [4.5, 4.5], [1.8, 1.8], 0.0, 0.0, 4.5, 1.8, 0.4, 3.0, 3.0)
    assert v == pytest.approx(np.sqrt(135.0))  # the car in the next lane (3.5 m across) is not in the strip
    assert follow_speed([[10.0, 3.5]], [4.5], [1.8], 0.0, 0.0, 4.5, 1.8, 0.4, 3.0, 3.0) == np.inf
