"""Links of the ego's own edge whose internal lanes cross its own although the junction logic makes neither give
way (issue 34; netconvert's joined junctions draw them so: the unseen Sao Paulo district, a left turn from the left
lane swinging across the straight-on from the lane beside it, both green at once). Here netconvert builds such a
junction from a connection with its own shape (``RouteLink.crossers``); SUMO lets both go, and the ego lets the
left-turner go first."""
from __future__ import annotations

import pathlib
import subprocess

import pytest
import sumo
import sumolib

from sumo_avoid.road.right_of_way import RightOfWay
from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario

pytestmark = pytest.mark.sumo
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
NODES = ('<nodes><node id="W" x="-200" y="0"/><node id="C" x="0" y="0" type="priority"/><node id="E" x="200" y="0"/>'
         '<node id="N" x="0" y="200"/><node id="S" x="0" y="-200"/></nodes>')
EDGES = ('<edges><edge id="WC" from="W" to="C" numLanes="2" speed="13.89" priority="2"/>'
         '<edge id="CE" from="C" to="E" numLanes="2" speed="13.89" priority="2"/>'
         '<edge id="EC" from="E" to="C" numLanes="2" speed="13.89" priority="2"/>'
         '<edge id="CN" from="C" to="N" numLanes="1" speed="13.89" priority="1"/>'
         '<edge id="SC" from="S" to="C" numLanes="1" speed="13.89" priority="1"/></edges>')
# the left turn from WC's left lane first swings right, across the straight-on from its right lane
CONNECTIONS = ('<connections><connection from="WC" to="CE" fromLane="0" toLane="0"/>'
               '<connection from="WC" to="CN" fromLane="1" toLane="0" shape="-8.0,-1.6 -2.0,-7.0 4.0,-2.0 4.8,8.0"/>'
               '</connections>')
ROUTES = """<routes>
  <vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="20"/>
  <vType id="car" length="4.5" width="1.8" accel="2.6" decel="4.5" maxSpeed="14" sigma="0"/>
  <vehicle id="ego" type="ego_car" depart="0" departLane="0" departPos="150" departSpeed="8"><route edges="WC CE"/></vehicle>
  <vehicle id="lefty" type="car" depart="0" departLane="1" departPos="153" departSpeed="8"><route edges="WC CN"/></vehicle>
</routes>"""


def _net(tmp_path) -> pathlib.Path:
    for name, text in (("c.nod.xml", NODES), ("c.edg.xml", EDGES), ("c.con.xml", CONNECTIONS)):
        (tmp_path / name).write_text(text)
    net = tmp_path / "c.net.xml"
    subprocess.run([str(BIN / "netconvert"), "-n", str(tmp_path / "c.nod.xml"), "-e", str(tmp_path / "c.edg.xml"),
                    "-x", str(tmp_path / "c.con.xml"), "--offset.disable-normalization", "true",
                    "--no-turnarounds", "true", "-o", str(net)], check=True, capture_output=True)
    return net


def test_a_link_of_the_same_edge_crossing_without_right_of_way_is_a_crosser(tmp_path):
    net = sumolib.net.readNet(str(_net(tmp_path)), withInternal=True, withFoes=True)
    row, node = RightOfWay(net), net.getNode("C")
    straight, left = (next(c for c in node.getConnections() if c.getFromLane().getID() == lane) for lane in ("WC_0", "WC_1"))
    assert not node.forbids(straight, left) and not node.forbids(left, straight)  # SUMO lets both go
    (foe,) = row.crossers(straight)
    assert foe.direction == "l" and dict(foe.approach).keys() >= {"WC_1", left.getViaLaneID()}
    assert [f.direction for f in row.crossers(left)] == ["s"]
    assert row.crossers(next(c for c in node.getConnections() if c.getFromLane().getID() == "EC_0")) == ()


def test_the_ego_lets_a_crossing_left_turner_of_its_own_edge_go_first(tmp_path):
    """Both 45 m before the junction at 8 m/s side by side (the left-turner 3 m ahead): the ego waits at its line
    until the left-turner has crossed its path, then goes; no contact."""
    _net(tmp_path)
    (tmp_path / "c.rou.xml").write_text(ROUTES)
    (tmp_path / "c.toml").write_text('name = "crossers"\n[sim]\nnet = "c.net.xml"\nroutes = ["c.rou.xml"]\n'
                                     'duration_s = 40.0\n[ego]\nids = ["ego"]\nlayers = ["traffic"]\n'
                                     'cruise_speed_mps = 12.0\n')
    m = outputs.run_metrics(runner.run(scenario.load(tmp_path / "c.toml")))
    assert m["goal_reached"] and m["collisions"] == 0 and m["min_gap_m"] > 0.5
