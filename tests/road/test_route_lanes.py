"""The corridor of the ego's lanes along its path (road/route_lanes.py), pinned to hand-computed values."""
import numpy as np

from sumo_avoid.road.route_lanes import JUNCTION_MARGIN_M, RouteLanes
from sumo_avoid.road.route import LanePiece

# a 100 m two-lane edge (3.2 m lanes, the path on lane 0), a 10 m internal lane (3.0 m), a one-lane edge
PIECES = (
    LanePiece(0.0, 100.0, "A", 0, (0.0, 3.2), (0.0, 3.2), (3.2, 3.2)),
    LanePiece(100.0, 110.0, ":J_0", 0, (0.0,), (0.0,), (3.0,)),
    LanePiece(110.0, 200.0, "B", 0, (0.0,), (0.0,), (3.2,)),
)


def test_two_lanes_of_the_direction_then_the_taper_to_the_lane_that_continues():
    lo, hi = RouteLanes(PIECES).corridor([10.0, 70.0, 85.0, 100.0 - 1e-3])
    # both lanes: from 1.6 m right of lane 0's centre to 1.6 + 3.2 m left of it
    assert np.allclose(lo[:2], -1.6) and np.allclose(hi[:2], 4.8)
    # the last 30 m taper linearly to lane 0 alone: half-way (s = 85) the left bound is at 3.2
    assert np.isclose(hi[2], 3.2, atol=1e-4) and np.isclose(hi[3], 1.6, atol=1e-3)
    assert np.allclose(lo[2:], -1.6, atol=1e-4)


def test_inside_a_junction_the_internal_lane_is_widened_with_ramps_at_its_ends():
    lo, hi = RouteLanes(PIECES).corridor([100.0 + 1.5, 105.0, 110.0 - 1e-4, 150.0])
    # ramp 3 m: 1.5 m in, half the margin
    assert np.isclose(hi[0], 1.5 + 0.5 * JUNCTION_MARGIN_M, atol=1e-4)
    assert np.isclose(lo[1], -1.5 - JUNCTION_MARGIN_M) and np.isclose(hi[1], 1.5 + JUNCTION_MARGIN_M)
    assert np.isclose(hi[3], 1.6) and np.isclose(lo[3], -1.6)


def test_lanes_that_do_not_continue_end_where_their_taper_starts():
    """Edge A (0 .. 100 m) tapers its other lanes over the last 30 m: a car in lane 1 must be out
    by s = 70; on the last edge (nothing follows) the lanes end with it, at 200."""
    lanes = RouteLanes(PIECES)
    assert lanes.lanes_end_s(10.0) == 70.0 and lanes.lanes_end_s(99.0) == 70.0
    assert lanes.lanes_end_s(150.0) == 200.0
    # a 40 m edge entered on the other lane: the blend piece (0 .. 20) and the rest (20 .. 40) are
    # one edge; the taper is at most half the last piece: 40 - min(30, 10) = 30
    blend = (LanePiece(0.0, 20.0, "A", 1, (0.0, 3.2), (-3.2, 0.0), (3.2, 3.2)),
             LanePiece(20.0, 40.0, "A", 1, (-3.2, 0.0), (-3.2, 0.0), (3.2, 3.2)),
             LanePiece(40.0, 50.0, ":J_0", 0, (0.0,), (0.0,), (3.0,)))
    assert RouteLanes(blend).lanes_end_s(5.0) == 30.0
