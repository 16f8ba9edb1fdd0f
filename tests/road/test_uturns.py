"""U-turns (road/uturns.py): a route's turnarounds, and the fastest route round them.

Real nets built by SUMO's own tools: a netgenerate grid (3 x 3 junctions 80 m apart, one lane each way;
turnarounds where a street meets the grid's edge) and a netconvert street with a dead end at each
end. The run: an APF-SA ego whose route turns back at a grid junction drives round the block to the
same last edge, on the road, instead of standing before a turn it cannot make."""
import pathlib
import subprocess

import pytest
import sumo
import sumolib

from sumo_avoid.road.polyline import polyline_length
from sumo_avoid.road.uturns import is_uturn, uturns, without_uturns
from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"


@pytest.fixture(scope="module")
def nets(tmp_path_factory):
    d = tmp_path_factory.mktemp("uturns")
    subprocess.run([str(BIN / "netgenerate"), "--grid", "--grid.number", "3", "--grid.length", "80",
                    "--default.lanenumber", "1", "-o", str(d / "grid.net.xml")], check=True, capture_output=True)
    (d / "s.nod.xml").write_text('<nodes><node id="A" x="0" y="0"/><node id="B" x="200" y="0"/></nodes>')
    (d / "s.edg.xml").write_text('<edges><edge id="AB" from="A" to="B" numLanes="1"/>'
                                 '<edge id="BA" from="B" to="A" numLanes="1"/></edges>')
    subprocess.run([str(BIN / "netconvert"), "-n", str(d / "s.nod.xml"), "-e", str(d / "s.edg.xml"),
                    "-o", str(d / "street.net.xml")], check=True, capture_output=True)
    return d


def test_a_turnaround_is_found_and_driven_round_the_block(nets):
    net = sumolib.net.readNet(str(nets / "grid.net.xml"))
    assert is_uturn(net.getEdge("A0B0"), net.getEdge("B0A0"), "passenger")
    assert not is_uturn(net.getEdge("A0B0"), net.getEdge("B0B1"), "passenger")
    assert uturns(net, ["A0B0", "B0A0"], "passenger") == [0]
    route = without_uturns(net, ["A0B0", "B0A0"], "passenger")
    # round one block: out along the grid's edge or into it, three sides of a block, back onto B0A0 at B0
    assert route in (("A0B0", "B0C0", "C0C1", "C1B1", "B1B0", "B0A0"),
                     ("A0B0", "B0B1", "B1C1", "C1C0", "C0B0", "B0A0"))
    assert uturns(net, route, "passenger") == []
    assert all(net.getEdge(b) in net.getEdge(a).getOutgoing() for a, b in zip(route, route[1:]))
    assert without_uturns(net, ["A0B0", "B0A0"], "passenger") == route  # the same every time


def test_a_route_without_turnaround_is_kept(nets):
    net = sumolib.net.readNet(str(nets / "grid.net.xml"))
    assert without_uturns(net, ["A0B0", "B0B1", "B1C1"], "passenger") is None
    assert without_uturns(net, ["A0B0"], "passenger") is None


def test_a_turnaround_at_a_dead_end_cannot_be_avoided(nets):
    net = sumolib.net.readNet(str(nets / "street.net.xml"))
    assert uturns(net, ["AB", "BA"], "passenger") == [0]
    assert without_uturns(net, ["AB", "BA"], "passenger") is None


@pytest.mark.sumo
def test_an_ego_drives_round_a_turnaround_on_the_road(nets, tmp_path):
    (tmp_path / "u.rou.xml").write_text(
        '<routes>\n  <vType id="car" length="5" width="1.8" accel="2.6" decel="4.5" maxSpeed="20"/>\n'
        '  <vehicle id="ego" type="car" depart="0" departPos="10"><route edges="A0B0 B0A0"/></vehicle>\n</routes>\n')
    (tmp_path / "u.toml").write_text(
        f'name = "uturn"\n[sim]\nnet = "{nets / "grid.net.xml"}"\nroutes = ["u.rou.xml"]\nstep_s = 0.1\n'
        'duration_s = 120.0\nseed = 1\n[ego]\nids = ["ego"]\ncontroller = "apf_sa"\ncruise_speed_mps = 10.0\n'
        '')
    res = runner.run(scenario.load(tmp_path / "u.toml"))
    m = outputs.run_metrics(res)
    assert m["goal_reached"] and m["collisions"] == 0 and m["off_road_m"] == 0.0 and m["phi_wall"] <= 0.1
    assert polyline_length(res.tasks["ego"].path) > 5 * 80 - 40  # round the block, not on the spot
    assert m["path_length_m"] > 5 * 80 - 40 and m["route_detours"] == 1
    given, driven = res.detours["ego"]
    assert given == ("A0B0", "B0A0") and len(driven) == 6 and driven[0] == "A0B0" and driven[-1] == "B0A0"
