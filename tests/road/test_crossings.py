"""Crossings and lane permissions on an ego's route, on nets netconvert builds here from plain XML:
a street with a zebra (crossing with priority) and sidewalks; a street with a sidewalk, a bike lane
and a car lane; a signalised crossroads with guessed crossings."""
from __future__ import annotations

import pathlib
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import sumo

from sumo_avoid.road.crossings import CrossingLink, persons_at
from sumo_avoid.road.network import Road
from sumo_avoid.road.route_lanes import RouteLanes

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
NODES = ('<nodes><node id="W" x="-250" y="0" type="priority"/><node id="Z" x="0" y="0" type="{z}"/>'
         '<node id="E" x="250" y="0" type="priority"/><node id="N" x="0" y="250" type="priority"/>'
         '<node id="S" x="0" y="-250" type="priority"/></nodes>')


def _net(d: pathlib.Path, edges: str, con: str = "", z: str = "priority", *extra: str) -> Road:
    (d / "n.nod.xml").write_text(NODES.format(z=z))
    (d / "n.edg.xml").write_text(f"<edges>{edges}</edges>")
    args = [str(BIN / "netconvert"), "-n", str(d / "n.nod.xml"), "-e", str(d / "n.edg.xml"), "--no-turnarounds",
            "true", "--offset.disable-normalization", "true", "-o", str(d / "n.net.xml"), *extra]
    if con:
        (d / "n.con.xml").write_text(f"<connections>{con}</connections>")
        args += ["-x", str(d / "n.con.xml")]
    subprocess.run(args, check=True, capture_output=True)
    return Road.from_net_file(d / "n.net.xml")


def _two_way(a: str, b: str, lanes: str = 'numLanes="1" sidewalkWidth="2.5"') -> str:
    return f'<edge id="{a}{b}" from="{a}" to="{b}" {lanes}/><edge id="{b}{a}" from="{b}" to="{a}" {lanes}/>'


@pytest.fixture(scope="module")
def zebra(tmp_path_factory) -> Road:
    return _net(tmp_path_factory.mktemp("zebra"), _two_way("W", "Z") + _two_way("Z", "E"),
                '<crossing node="Z" edges="ZE EZ" priority="true" width="4"/>')


def test_a_zebra_on_the_route_gives_people_way(zebra):
    plan = zebra.route(["WZ", "ZE"], vclass="passenger")
    (link,) = plan.links
    (c,) = link.crossings
    assert c.crossing == ":Z_c0" and c.lane == ":Z_c0_0" and c.gives_way and c.tls == ""
    # the crossing is 4 m wide, across ZE where it leaves Z (x = 0 .. the junction's shape): the ego's
    # path enters it after its stop line and leaves it 4 m later (sampled every 0.1 m)
    assert link.s_stop_m <= c.s_enter_m < c.s_exit_m
    assert c.s_exit_m - c.s_enter_m == pytest.approx(3.8, abs=0.15)
    assert set(c.walking_areas) == {":Z_w0_0", ":Z_w1_0"}
    # the way back (EZ, ZW) passes over no crossing: the zebra is on the east arm only
    assert all(not lk.crossings for lk in zebra.route(["EZ", "ZW"], vclass="passenger").links) or \
        all(c2.crossing == ":Z_c0" for lk in zebra.route(["EZ", "ZW"], vclass="passenger").links for c2 in lk.crossings)


def test_persons_on_the_crossing_or_stepping_onto_it():
    c = CrossingLink(":Z_c0", ":Z_c0_0", (":Z_w0_0", ":Z_w1_0"), ((2.0, -6.0), (2.0, 6.0)), 248.0, 252.0, True)
    lanes = [":Z_c0_0", ":Z_w0_0", ":Z_w0_0", ":Z_w0_0", ":Z_w1_0", "ZE_0"]
    pos = np.array([[2.0, 0.0], [2.0, -7.0], [2.0, -7.0], [2.0, -9.5], [2.0, 7.0], [5.0, -6.0]])
    vel = np.array([[0.0, 1.2], [0.0, 1.0], [0.0, -1.0], [0.0, 1.0], [0.0, 0.0], [0.0, 1.0]])
    # on it; walking towards it 1 m from its end; walking away; 3.5 m away (beyond the kerb zone);
    # standing at the kerb of the far end; on a sidewalk lane
    assert persons_at(c, lanes, pos, vel).tolist() == [True, True, False, False, True, False]


@pytest.fixture(scope="module")
def bike_street(tmp_path_factory) -> Road:
    lanes = ('<lane index="0" allow="pedestrian" width="2.0"/><lane index="1" allow="bicycle" width="1.5"/>'
             '<lane index="2" width="3.2"/>')
    edges = "".join(f'<edge id="{a}{b}" from="{a}" to="{b}" numLanes="3">{lanes}</edge>'
                    for a, b in (("W", "Z"), ("Z", "W"), ("Z", "E"), ("E", "Z")))
    return _net(tmp_path_factory.mktemp("bike"), edges)


def test_the_route_frame_of_a_car_ends_at_the_bike_lane(bike_street):
    car = bike_street.route(["WZ", "ZE"], vclass="passenger")
    bike = bike_street.route(["WZ", "ZE"], depart_lane=1, vclass="bicycle")
    assert [p.lane for p in car.lanes if not p.edge.startswith(":")] == [2, 2], [(p.edge, p.lane) for p in car.lanes]
    first = car.lanes[0]
    assert first.allowed == (False, False, True) and bike.lanes[0].allowed == (False, True, True)  # bikes may use the road
    lo, hi = RouteLanes(car.lanes).corridor([100.0])
    assert (lo[0], hi[0]) == pytest.approx((-1.6, 1.6))  # the car lane alone (3.2 m), not the 5.5 m to the kerb
    lo_all, _ = RouteLanes(bike_street.route(["WZ", "ZE"], depart_lane=2).lanes).corridor([100.0])
    assert lo_all[0] == pytest.approx(-1.6 - 1.5 - 2.0)  # without a class: every lane, as before
    assert not bike_street.route(["WZ"], vclass="passenger").lanes[0].allowed[0]  # a one-edge route: lane 2
    assert bike_street.route(["WZ"], vclass="passenger").lanes[0].lane == 2


@pytest.fixture(scope="module")
def signalised(tmp_path_factory) -> Road:
    edges = "".join(_two_way("Z", x, 'numLanes="1" sidewalkWidth="2.5"') for x in "WENS")
    return _net(tmp_path_factory.mktemp("tls"), edges, "", "traffic_light", "--crossings.guess", "true")


def test_a_turn_at_a_light_gives_way_to_people_on_its_exit_crossing(signalised):
    right = signalised.route(["WZ", "ZS"], vclass="passenger").links[0]
    straight = signalised.route(["WZ", "ZE"], vclass="passenger").links[0]
    # crossings: the entry arm's (before the junction) and the exit arm's; each signalised
    assert {len(right.crossings), len(straight.crossings)} <= {1, 2} and right.crossings and straight.crossings
    assert all(c.tls == "Z" and c.link_index >= 0 for c in right.crossings + straight.crossings)
    exit_right, exit_straight = right.crossings[-1], straight.crossings[-1]
    assert exit_right.gives_way  # turning right across people walking on green: give way to them
    # going straight the link would give way too, but the two are never green together (the program)
    states = [ph.get("state") for ph in ET.parse(signalised.source).getroot().iter("phase")]
    green = [s for s in states if s[straight.link_index] in "Gg" and s[exit_straight.link_index] in "Gg"]
    assert states and green == []
    assert any(s[right.link_index] in "Gg" and s[exit_right.link_index] in "Gg" for s in states)


def test_a_person_past_the_egos_path_or_standing_beside_it_does_not_hold_it():
    # the crossing runs from y = -6 to y = 6 along x = 2; the ego's path passes over y in [-2.6, -0.6]
    # (strip measured from the first end: 3.4 .. 5.4 m); footprint half width 0.9 + margin 1 m: the
    # persons that hold it are within [1.5, 7.3] m of the first end, or walk towards that stretch from
    # at most 3 m (gap)
    c = CrossingLink(":Z_c0", ":Z_c0_0", (":Z_w0_0", ":Z_w1_0"), ((2.0, -6.0), (2.0, 6.0)), 248.0, 252.0, True,
                     strip=(3.4, 5.4))
    lanes = [":Z_c0_0"] * 7 + [":Z_w0_0"]
    pos = np.array([[2.0, -1.5], [2.0, 2.0], [2.0, 3.0], [2.0, 3.0], [2.0, -5.0], [2.0, -3.0], [2.0, 1.0],
                    [2.0, -7.9], [2.0, -4.5]])
    vel = np.array([[0.0, 0.0], [0.0, 1.2], [0.0, -1.2], [0.0, 0.0], [0.0, -1.2], [0.0, 1.2], [0.0, -1.2],
                    [0.0, 1.0], [0.0, 1.2]])
    lanes.append(":Z_c0_0")
    # standing in the strip; walked past it (u 8 > 7.3); 1.7 m beyond it walking back towards it; standing
    # 1.7 m beyond it; 0.5 m before it walking away; u 3.0: inside; u 7.0: inside; stepping onto the crossing
    # from the walking area at u -1.9, 3.4 m before the stretch (beyond the 3 m gap); at u 1.5, the
    # stretch's edge: held
    held = persons_at(c, lanes, pos, vel, half_width_m=1.9, gap_m=3.0)
    assert held.tolist() == [True, False, True, False, False, True, True, False, True]
    # without a half width (the whole crossing) every one on it or stepping onto it holds it
    assert persons_at(c, lanes, pos, vel).tolist() == [True] * 9


def test_after_the_peoples_green_only_those_on_the_crossing_hold_and_a_horizon_shortens_the_reach():
    c = CrossingLink(":Z_c0", ":Z_c0_0", (":Z_w0_0", ":Z_w1_0"), ((2.0, -6.0), (2.0, 6.0)), 248.0, 252.0, True,
                     strip=(3.4, 5.4))
    # the stretch's margin begins at u = 1.5: one on the crossing at u 1.0 walking at 1.25 m/s (0.5 m, 0.4 s
    # away); one at the kerb 1 m before the crossing walking onto it (2.5 m); one on a sidewalk in line with
    # it 2 m beyond its end (3.5 m)
    lanes = [":Z_c0_0", ":Z_w0_0", "ZE_0"]
    pos = np.array([[2.0, -5.0], [2.0, -7.0], [2.0, -8.0]])
    vel = np.array([[0.0, 1.25], [0.0, 1.2], [0.0, 1.2]])
    assert persons_at(c, lanes, pos, vel, 1.9, 10.0).tolist() == [True, True, True]
    assert persons_at(c, lanes, pos, vel, 1.9, 10.0, on_only=True).tolist() == [True, False, False]
    # within 1.5 s a walker covers 1.8-1.9 m: the one on the crossing still holds, the others not
    assert persons_at(c, lanes, pos, vel, 1.9, 10.0, horizon_s=1.5).tolist() == [True, False, False]
    assert persons_at(c, lanes, pos, vel, 1.9, 10.0, horizon_s=0.3).tolist() == [False, False, False]


def test_the_walkways_are_the_sidewalks_and_walking_areas(zebra):
    w = zebra.elements.walkways
    assert {":Z_w0_0", ":Z_w1_0", "WZ_0", "ZE_0"} <= w
    assert ":Z_c0_0" not in w and "WZ_1" not in w and not any(lane.startswith(":Z_c") for lane in w)
