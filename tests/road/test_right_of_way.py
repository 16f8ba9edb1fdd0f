"""Right of way read from the net (road/right_of_way.py) at an unregulated crossroads
(tests/data/unregulated, built here by netconvert: four one-lane arms, right-hand traffic), where
SUMO's junction logic is empty and every link is 'M'. The ego going straight from the south gives
way (state '=') to every link from another arm that crosses its path or ends in its lane, worked
out by hand: from the east right (merges into CN), straight and left; from the north left; from
the west straight and left (merges). Not: from the north straight and right, from the west right."""
import pytest
import sumolib
from conftest import netconvert

from sumo_avoid.runs import outputs
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.road.right_of_way import RightOfWay, link_state


@pytest.fixture(scope="module")
def crossroads(tmp_path_factory):
    d = tmp_path_factory.mktemp("unregulated")
    netconvert("unregulated", d, "x")
    return d


def test_at_an_unregulated_junction_the_ego_gives_way_to_every_crossing_link(crossroads):
    net = sumolib.net.readNet(str(crossroads / "x.net.xml"), withInternal=True)
    conn = net.getEdge("SC").getConnections(net.getEdge("CN"))[0]
    assert conn.getState() == "M" and link_state(conn) == "="
    foes = RightOfWay(net).foes(conn)
    got = sorted((next(lane for lane, _ in f.approach if not lane.startswith(":")), f.direction) for f in foes)
    assert got == [("EC_0", "l"), ("EC_0", "r"), ("EC_0", "s"), ("NC_0", "l"), ("WC_0", "l"), ("WC_0", "s")]
    assert all(0.0 < f.line_m < 20.0 for f in foes)  # the conflict points lie inside the junction


@pytest.mark.sumo
def test_the_ego_waits_for_the_car_crossing_an_unregulated_junction(crossroads):
    """The ego from the south and a car from the west, both 80 m out at 10 m/s: SUMO's car does not
    look, SUMO checks no collision there. Before, the ego went too and the footprints met (SUMO saw
    nothing); now it gives way once and passes behind the car."""
    (crossroads / "x.rou.xml").write_text(
        '<routes>\n  <vType id="car" length="4.5" width="1.8" accel="2.6" decel="4.5" maxSpeed="10"/>\n'
        '  <vehicle id="ego" type="car" depart="0" departPos="20" departSpeed="10"><route edges="SC CN"/></vehicle>\n'
        '  <vehicle id="bg" type="car" depart="0" departPos="20" departSpeed="10"><route edges="WC CE"/></vehicle>\n'
        '</routes>\n')
    (crossroads / "x.toml").write_text('name = "unregulated"\n[sim]\nnet = "x.net.xml"\nroutes = ["x.rou.xml"]\n'
                                       'step_s = 0.1\nduration_s = 30.0\nseed = 1\n[ego]\nids = ["ego"]\n'
                                       'controller = "apf_sa"\ncruise_speed_mps = 10.0\n')
    m = outputs.run_metrics(runner.run(scenario.load(crossroads / "x.toml")))
    assert m["goal_reached"] and m["collisions"] == 0 and m["min_gap_m"] > 2.0
    assert m["rules_yields"] >= 1 and m["yield_violations"] == 0


def test_which_lanes_give_way_to_a_link():
    """nets/left_turn (a priority crossroads, two lanes per arm): the left turn from the south
    (S2C_1 -> C2W, minor) gives way to the oncoming straight (N2C -> C2S, major), not the other way;
    at the unregulated crossroads nobody gives way to anybody (SUMO's drivers go through)."""
    from conftest import ROOT

    net = sumolib.net.readNet(str(ROOT / "nets" / "left_turn.net.xml"), withInternal=True)
    row = RightOfWay(net)
    left = next(c for c in net.getLane("S2C_1").getOutgoing() if c.getTo().getID() == "C2W")
    straight = next(c for c in net.getLane("N2C_0").getOutgoing() if c.getTo().getID() == "C2S")
    assert row.gives_way_to(net.getLane("S2C_1"), straight) is True  # its left turn yields to the straight
    assert row.gives_way_to(net.getLane("N2C_0"), left) is False  # nothing from N2C_0 yields to a minor left
    assert row.gives_way_to(net.getLane("N2C_1"), left) is False


def test_nobody_gives_way_at_an_unregulated_junction(crossroads):
    net = sumolib.net.readNet(str(crossroads / "x.net.xml"), withInternal=True)
    conn = net.getEdge("SC").getConnections(net.getEdge("CN"))[0]
    assert not any(RightOfWay(net).gives_way_to(lane, conn) for e in ("EC", "NC", "WC") for lane in net.getEdge(e).getLanes())


def test_who_is_in_the_junction_clears_it_first():
    """nets/left_turn: for the major straight from the north (N2C_0 -> C2S), the minor left turn from the
    south (S2C_1 -> C2W), which crosses it, is a link *inside*: only its internal lanes, none before its
    stop line (a car there waits for the straight; one in the junction clears it). The straight, with
    priority over the left turn, is that one's foe, not its link inside."""
    from conftest import ROOT

    net = sumolib.net.readNet(str(ROOT / "nets" / "left_turn.net.xml"), withInternal=True)
    row = RightOfWay(net)
    left = next(c for c in net.getLane("S2C_1").getOutgoing() if c.getTo().getID() == "C2W")
    straight = next(c for c in net.getLane("N2C_0").getOutgoing() if c.getTo().getID() == "C2S")
    inside = row.inside(straight)
    via = {v.getID() for v in row.via_chain(left)}
    mine = [f for f in inside if {lane for lane, _ in f.approach} <= via]
    assert len(mine) == 1 and mine[0].direction == "l"
    assert all(lane.startswith(":") for f in inside for lane, _ in f.approach)
    assert all(0.0 <= off <= sum(v.getLength() for v in row.via_chain(left)) for _, off in mine[0].approach)
    assert not any({lane for lane, _ in f.approach} & {v.getID() for v in row.via_chain(straight)}
                   for f in row.inside(left))  # the straight is the left turn's foe, not inside
    assert any(lane == "N2C_0" for f in row.foes(left) for lane, _ in f.approach)
