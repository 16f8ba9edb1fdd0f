"""Where SUMO is told the ego is (sumo/placement.py), on the real left_turn net (two-way arms):
on its route -> keepRoute=1 with the lane; in the oncoming lane -> off route (keepRoute=2, no
hint); back on -> the lane as a hint and the rest of the original route to set again."""
import pathlib

import numpy as np

from sumo_avoid.core.types import EgoTask
from sumo_avoid.sumo.placement import OFF_ROUTE, ON_ROUTE, RoutePlacement
from sumo_avoid.road.network import Road

NET = pathlib.Path(__file__).parent.parent.parent / "nets" / "left_turn.net.xml"


def test_on_off_and_back_on_route():
    road = Road.from_net_file(NET)
    edges = ("S2C", "C2W")
    plan = road.route(list(edges), depart_lane=1)
    task = EgoTask("ego", plan.path[-1], plan.path, 10.0, plan.links, plan.speed_limits, plan.lanes)
    pl = RoutePlacement()
    pl.follow(task, edges)
    on = road.lane_centre_at("S2C", 1, 100.0)
    assert pl.place("ego", on) == ("S2C", 1, ON_ROUTE, ())
    right = road.lane_centre_at("S2C", 0, 110.0)
    assert pl.place("ego", right) == ("S2C", 0, ON_ROUTE, ())
    oncoming = road.lane_centre_at("C2S", 1, 239.0 - 120.0)  # the other direction's lane beside it
    assert pl.place("ego", oncoming) == ("", -1, OFF_ROUTE, ())
    back = road.lane_centre_at("S2C", 1, 130.0)
    assert pl.place("ego", back) == ("S2C", 1, OFF_ROUTE, edges)  # the route to set again
    assert pl.place("ego", road.lane_centre_at("S2C", 1, 140.0)) == ("S2C", 1, ON_ROUTE, ())
    turn = plan.path[np.argmin(np.abs(np.cumsum(np.r_[0, np.hypot(*np.diff(plan.path, axis=0).T)]) - 250.0))]
    edge, _, mode, _ = pl.place("ego", turn)
    assert edge.startswith(":C_") and mode == ON_ROUTE
    pl.forget("ego")
    assert pl.place("ego", on) == ("", -1, OFF_ROUTE, ())  # not followed: anywhere
