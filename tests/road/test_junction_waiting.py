"""Where a signalised turn waits inside the junction, and which points are on walkways, on the streets
library's signalised crossroads (scenarios/streets/signal_crossing.net.xml, built by netconvert)."""
from __future__ import annotations

import math
import pathlib

import numpy as np
import pytest

from sumo_avoid.road.network import Road

NET = pathlib.Path(__file__).parents[2] / "scenarios" / "streets" / "signal_crossing.net.xml"


@pytest.fixture(scope="module")
def road() -> Road:
    return Road.from_net_file(NET)


def test_a_left_turn_waits_past_its_stop_line_clear_of_the_oncoming_path(road):
    plan = road.route(["S2C", "C2W"], depart_lane=2, vclass="passenger")
    (link,) = plan.links
    assert link.tls == "C" and link.s_stop_m < link.s_wait_m == link.yield_line_m < link.s_stop_m + 5.0
    # the oncoming straight lane N2C_2 runs down x = -1.6 through the junction: at the wait line the front
    # corners of a 2 m wide car on the path keep 1.8 m from it, 0.25 m further on they would not
    cum = np.r_[0.0, np.cumsum(np.hypot(*np.diff(plan.path, axis=0).T))]

    def corner_gap(s):
        x, y = np.interp(s, cum, plan.path[:, 0]), np.interp(s, cum, plan.path[:, 1])
        tx, ty = np.interp(s + 0.5, cum, plan.path[:, 0]) - x, np.interp(s + 0.5, cum, plan.path[:, 1]) - y
        n = math.hypot(tx, ty)
        left_x = x - 1.0 * ty / n
        return left_x - (-1.6)

    assert corner_gap(link.s_wait_m) >= 1.8 > corner_gap(link.s_wait_m + 0.25)
    # a right turn has no foe crossing its way with green at the same time: it gives way at its stop line
    (right,) = road.route(["S2C", "C2E"], depart_lane=1, vclass="passenger").links
    assert math.isnan(right.s_wait_m) and right.yield_line_m == right.s_stop_m


def test_walkways_are_the_sidewalks_and_corners_not_the_road_or_the_crossings(road):
    # S2C: sidewalk x 6.4 .. 8.9, car lanes x 0 .. 6.4; the crossing of the south arm spans y -20.9 .. -16.9;
    # a person waiting on the end of that crossing (6.6, -18.2); a point 0.15 m into the car lane counts (0.3 m
    # tolerance: a radar return lies on a person's near side)
    pts = np.array([[7.65, -100.0], [4.8, -100.0], [0.0, -18.9], [6.6, -18.2], [6.55, -100.0]])
    assert road.on_walkway(pts).tolist() == [True, False, False, True, True]


def test_the_junction_corridor_never_widens_over_a_walkway(road):
    # through the crossroads and right round its corner: inside the junction the corridor is the internal
    # lane widened by JUNCTION_MARGIN_M, but not into the walking areas at the corners (people stand there)
    from sumo_avoid.road.frenet import RouteFrame
    from sumo_avoid.road.route_lanes import JUNCTION_MARGIN_M, RouteLanes

    for edges, lane in ((["S2C", "C2N"], 1), (["S2C", "C2E"], 1)):
        plan = road.route(edges, depart_lane=lane, vclass="passenger")
        inner = [p for p in plan.lanes if p.edge.startswith(":")]
        # a walking area at the right corner: within the walkway tolerance (0.3 m) of the lane's border
        assert inner and all(p.kerb_room_m[0] == 0.0 for p in inner)
        lanes, frame = RouteLanes(plan.lanes), RouteFrame.from_polyline(plan.path)
        s = np.linspace(inner[0].s_start_m, inner[-1].s_end_m, 40)
        lo, hi = lanes.corridor(s)
        assert lo.min() >= -1.6 - 1e-6  # the right bound is the internal lane's own border (3.2 m wide)
        # 0.1 m beyond it is a walkway somewhere along the junction (what the bound keeps the car from)
        assert road.on_walkway(frame.to_xy(s, lo - 0.1)).any()
        # where no walkway is near, the corridor still widens (the left side of the straight route)
        if edges[1] == "C2N":
            mid = s[len(s) // 2]
            assert lanes.corridor([mid])[1][0] - 1.6 == pytest.approx(JUNCTION_MARGIN_M, abs=0.05)
