"""Where the route path changes lanes (road/route_plan.lane_costs): as few changes as any plan needs, and of those
the least steep, on a long edge rather than on the short piece a net splits off before a junction (unseen Chiang
Mai: changed only on the 15 m edge before the turn that needed it, the ego crossed it at 21 degrees into a queue,
stood on the diagonal and was clipped in the lane it left). netconvert builds a road of a 200 m edge and two 15 m
pieces, two lanes each, whose only way on to the north leaves from the left lane."""
from __future__ import annotations

import pathlib
import subprocess

import pytest
import sumo
import sumolib

from sumo_avoid.road.network import Road
from sumo_avoid.road.route_plan import lane_costs

pytestmark = pytest.mark.sumo
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
NODES = ('<nodes><node id="W" x="-230" y="0"/><node id="A" x="-30" y="0" type="priority"/>'
         '<node id="B" x="-15" y="0" type="priority"/><node id="C" x="0" y="0" type="priority"/>'
         '<node id="N" x="0" y="200"/><node id="E" x="200" y="0"/></nodes>')
EDGES = ('<edges><edge id="WA" from="W" to="A" numLanes="2" speed="13.89"/>'
         '<edge id="AB" from="A" to="B" numLanes="2" speed="13.89"/>'
         '<edge id="BC" from="B" to="C" numLanes="2" speed="13.89"/>'
         '<edge id="CN" from="C" to="N" numLanes="1" speed="13.89"/>'
         '<edge id="CE" from="C" to="E" numLanes="1" speed="13.89"/></edges>')
CONNECTIONS = ('<connections><connection from="BC" to="CN" fromLane="1" toLane="0"/>'
               '<connection from="BC" to="CE" fromLane="0" toLane="0"/></connections>')


@pytest.fixture(scope="module")
def net_file(tmp_path_factory) -> pathlib.Path:
    d = tmp_path_factory.mktemp("lanes")
    for name, text in (("n.nod.xml", NODES), ("n.edg.xml", EDGES), ("n.con.xml", CONNECTIONS)):
        (d / name).write_text(text)
    net = d / "n.net.xml"
    subprocess.run([str(BIN / "netconvert"), "-n", str(d / "n.nod.xml"), "-e", str(d / "n.edg.xml"),
                    "-x", str(d / "n.con.xml"), "--no-turnarounds", "true", "-o", str(net)], check=True, capture_output=True)
    return net


def test_lane_costs_by_hand(net_file):
    net = sumolib.net.readNet(str(net_file))
    edges = [net.getEdge(e) for e in ("WA", "AB", "BC", "CN")]
    lengths = [e.getLength() for e in edges]
    assert lengths[0] > 120.0 and max(lengths[1:3]) < 16.0  # blends: 60 m on WA, half the piece on AB and BC
    costs = lane_costs(edges, None, "passenger")
    assert costs[2] == {1: (0, 0.0), 0: (1, pytest.approx(1.0 / (0.5 * lengths[2])))}  # BC: only lane 1 goes north
    assert costs[0][1] == (0, 0.0)
    assert costs[0][0] == (1, pytest.approx(1.0 / 60.0))  # from lane 0 the one change is made on WA


def test_the_path_changes_lanes_on_the_long_edge(net_file):
    plan = Road.from_net_file(net_file).route(["WA", "AB", "BC", "CN"], depart_lane=0, vclass="passenger")
    normal = [p for p in plan.lanes if not p.edge.startswith(":")]
    blends = [p.edge for p in normal if p.offsets_start_m != p.offsets_end_m]
    assert blends == ["WA"]  # (before: on BC, 15 m, 3.2 m across)
    assert [(p.edge, p.lane) for p in normal if p.edge in ("AB", "BC")] == [("AB", 1), ("BC", 1)]
