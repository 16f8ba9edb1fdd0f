"""The carriageway along a route (sumo_avoid.road.carriageway): every lane of the route's direction
that goes on, tapered where a lane ends, widened where one begins."""
import pytest

from sumo_avoid.road.carriageway import Carriageway
from sumo_avoid.road.route import LanePiece

THREE = (-3.5, 0.0, 3.5)  # lane centres across the middle lane a path follows, m
W3 = (3.5, 3.5, 3.5)


def _piece(a, b, edge, lane, o0, o1=None, w=W3):
    return LanePiece(a, b, edge, lane, o0, o0 if o1 is None else o1, w)


def test_carriageway_keeps_every_lane_that_goes_on_through_a_junction():
    # 3 lanes -> junction (the path's internal lane) -> 3 lanes: the flock's walls stay the whole
    # carriageway (-5.25, 5.25) before, inside and after the junction
    way = Carriageway((_piece(0, 100, "a", 1, THREE), _piece(100, 110, ":j_0", 1, (0.0,), w=(3.5,)),
                       _piece(110, 200, "b", 1, THREE)))
    lo, hi = way.corridor([0.0, 85.0, 99.0, 105.0, 150.0, 250.0])
    assert lo == pytest.approx([-5.25] * 6) and hi == pytest.approx([5.25] * 6)


def test_carriageway_tapers_a_dropped_lane_and_widens_into_a_new_one():
    # 4 lanes (path on lane 1: centres -3.5, 0, 3.5, 7) -> 3 lanes (-3.5, 0, 3.5) -> 4 lanes again.
    four = (-3.5, 0.0, 3.5, 7.0)
    way = Carriageway((_piece(0, 100, "a", 1, four, w=(3.5,) * 4), _piece(100, 110, ":j_0", 1, (0.0,), w=(3.5,)),
                       _piece(110, 200, "b", 1, THREE), _piece(200, 210, ":k_0", 1, (0.0,), w=(3.5,)),
                       _piece(210, 300, "c", 1, four, w=(3.5,) * 4)))
    lo, hi = way.corridor([70.0, 85.0, 100.0, 105.0, 110.0, 200.0, 205.0, 210.0])
    assert lo == pytest.approx([-5.25] * 8)
    # the left lane ends in a taper over the last 30 m (8.75 -> 5.25), the new one opens through the
    # junction before it (5.25 -> 8.75 from s 200 to 210)
    assert hi == pytest.approx([8.75, 7.0, 5.25, 5.25, 5.25, 5.25, 7.0, 8.75])
