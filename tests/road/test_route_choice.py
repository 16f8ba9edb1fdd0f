"""Which lane the route takes where one lane fans out into several (tests/data/fan_out, built by
netconvert): the lane that goes on along the route, else the one that runs on straight rather than one
reached by a jog (a Bologna street, 116 -> 46, fans one lane into three with a 7.6 m jog to the right one;
the ego took it and its corner swept over the sidewalk into people walking there)."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from sumo_avoid.road.network import Road
from sumo_avoid.road.route_plan import _turning


@pytest.fixture(scope="module")
def road(tmp_path_factory) -> Road:
    from tests.conftest import netconvert

    return Road.from_net_file(netconvert("fan_out", tmp_path_factory.mktemp("fan"), "fan"))


def _lanes(plan):
    return [(p.edge, p.lane) for p in plan.lanes if not p.edge.startswith(":")]


def test_where_the_route_ends_it_takes_the_lane_that_runs_on_straight(road):
    plan = road.route(["AB", "BC"], vclass="passenger")
    assert _lanes(plan)[-1] == ("BC", 1)
    # no jog: the path stays on the line y = 0 all the way
    assert np.abs(plan.path[:, 1]).max() < 1e-6


def test_it_takes_the_lane_its_next_turn_leaves_from_rather_than_changing_lanes_later(road):
    def y_after_junction(plan):  # the path's lateral position 6 m into BC (lane centres y = -3.2, 0, 3.2)
        near = np.abs(plan.path[:, 0] - 110.0)
        seg = plan.path[(plan.path[:, 0] > 104.0) & (plan.path[:, 0] < 120.0)]
        return float(np.interp(110.0, seg[:, 0], seg[:, 1])) if len(seg) > 1 else float(plan.path[np.argmin(near), 1])

    left = road.route(["AB", "BC", "CD"], vclass="passenger")
    assert _lanes(left)[1] == ("BC", 2) and y_after_junction(left) == pytest.approx(3.2, abs=0.05)
    right = road.route(["AB", "BC", "CE"], vclass="passenger")
    assert _lanes(right)[1] == ("BC", 0) and y_after_junction(right) == pytest.approx(-3.2, abs=0.05)


def _conn(from_shape, to_shape):
    lane = lambda shape: SimpleNamespace(getShape=lambda: shape)  # noqa: E731
    return SimpleNamespace(getFromLane=lambda: lane(from_shape), getToLane=lambda: lane(to_shape))


def test_turning_sums_the_heading_changes_along_the_connection():
    # straight through: no turning
    assert _turning(_conn([(0, 0), (10, 0)], [(12, 0), (20, 0)]), []) == 0.0
    # a right angle through one internal lane (0,0)->(10,0)->(10,-10): pi/2
    via = SimpleNamespace(getShape=lambda: [(10, 0), (10, -10)])
    assert _turning(_conn([(0, 0), (10, 0)], [(10, -10), (10, -20)]), [via]) == pytest.approx(math.pi / 2)
    # a jog of 1 m over 1 m: 45 degrees right, then 45 degrees left
    assert _turning(_conn([(-1, 0), (0, 0)], [(1, -1), (2, -1)]), []) == pytest.approx(math.pi / 2)
