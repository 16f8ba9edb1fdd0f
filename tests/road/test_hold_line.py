"""Where the ego waits for a junction (RouteLink.s_hold_m, RightOfWay.hold_s): its stop line, or before it where
other links' turns through the junction sweep the stop line (netconvert's joined junctions on OpenStreetMap
districts: unseen Jaipur, cars turning through a cluster hit a car waiting at its line).

Hand-computed: RouteLink.hold_line_m. Real nets: on the project's netgenerate and netconvert nets no link moves;
on Berlin's Doerpfeldstrasse net (../shared/cities) every link that moves keeps its waiting car's front corners
1.2 m from the other links' paths, and does not at its stop line."""
import math

import numpy as np
import pytest
import shapely
import sumolib

from conftest import ROOT
from sumo_avoid.road.polyline import _cumlen
from sumo_avoid.road.right_of_way import RightOfWay, _chain_line
from sumo_avoid.road.route import RouteLink
from sumo_avoid.road.route_plan import HOLD_BACK_M, HOLD_CLEAR_M, WAIT_HALF_WIDTH_M

BERLIN = ROOT.parent / "shared" / "cities" / "berlin_doerpfeldstr" / "net.net.xml.gz"


@pytest.mark.parametrize("s_hold, v, line", [
    (97.0, 9.0, 97.0),  # 81 / 6 = 13.5 m <= 97 - 80 - 1 + 0.5 = 16.5 m: it waits at the hold line
    (97.0, 10.0, 100.0),  # 100 / 6 = 16.7 m > 16.5 m: too late for it, the stop line
    (math.nan, 0.0, 100.0),  # no hold line
    (100.0, 0.0, 100.0),  # the stop line itself
])
def test_hold_line_hand_computed(s_hold, v, line):
    link = RouteLink(100.0, "J", s_hold_m=s_hold)
    assert link.hold_line_m(80.0, v, 3.0, 1.0) == line


def _links(net):
    """(connection, path up to its stop line, stop-line arc length) of every car link with an internal lane."""
    for e in net.getEdges():
        if e.getFunction() != "":
            continue
        for ln in e.getLanes():
            for c in ln.getOutgoing():
                if ln.allows("passenger") and c.getViaLaneID():
                    path = np.asarray(ln.getShape(), float)
                    cum = _cumlen(path)
                    yield c, path, cum, float(cum[-1])


@pytest.mark.parametrize("net", ["scenarios/generated/grid01/grid01.net.xml", "scenarios/generated/rand08/rand08.net.xml",
                                 "scenarios/generated/spider03/spider03.net.xml", "scenarios/roads/grid_static.net.xml",
                                 "scenarios/streets/signal_crossing.net.xml", "nets/left_turn.net.xml"])
def test_clean_nets_keep_their_stop_lines(net):
    n = sumolib.net.readNet(str(ROOT / net), withInternal=True)
    row = RightOfWay(n)
    for c, path, cum, s_stop in _links(n):
        assert row.hold_s(c, path, cum, s_stop, HOLD_CLEAR_M, WAIT_HALF_WIDTH_M, HOLD_BACK_M) == s_stop


def _front_clearance(row, c, path, cum, s):
    """Least distance of a waiting car's front corners and front centre at arc length s to the other links' paths."""
    node = c.getFrom().getToNode()
    lines = [_chain_line(row.via_chain(o)) for o in node.getConnections()
             if o.getFrom() is not c.getFrom() and not o.getFromLane().getID().startswith(":")]
    x, y = np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])
    t = np.array([x - np.interp(s - 0.5, cum, path[:, 0]), y - np.interp(s - 0.5, cum, path[:, 1])])
    n = np.array([-t[1], t[0]]) / np.hypot(*t)
    pts = shapely.points([[x, y] + WAIT_HALF_WIDTH_M * n, [x, y] - WAIT_HALF_WIDTH_M * n, [x, y]])
    return min(float(shapely.distance(ln, pts).min()) for ln in lines if ln is not None)


@pytest.mark.skipif(not BERLIN.is_file(), reason="../shared/cities is not beside the checkout")
def test_a_joined_junction_moves_the_wait_back_until_the_turns_pass_clear():
    n = sumolib.net.readNet(str(BERLIN), withInternal=True)
    row = RightOfWay(n)
    moved = 0
    for c, path, cum, s_stop in _links(n):
        s = row.hold_s(c, path, cum, s_stop, HOLD_CLEAR_M, WAIT_HALF_WIDTH_M, HOLD_BACK_M)
        assert s_stop - HOLD_BACK_M - 1e-9 <= s <= s_stop
        if s < s_stop:
            moved += 1
            assert _front_clearance(row, c, path, cum, s_stop) < HOLD_CLEAR_M  # a turn sweeps the stop line
            assert _front_clearance(row, c, path, cum, s) >= HOLD_CLEAR_M - 1e-9  # and passes clear of the wait
    assert moved >= 10  # (55 of its 636 car links, measured)
