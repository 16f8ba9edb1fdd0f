"""Lane shapes with hooks on real SUMO (nets netconvert builds here, issue 34): a short edge between two
junctions whose lanes are laid apart, as OSM-derived nets have them (unseen Colonias' 376317858#4: 0.29 m
long, its lane 1 12 m behind its lane 2). The route's path has no out-and-back spur
(:func:`sumo_avoid.road.polyline.cut_spurs`) and APF-SA drives it without standing at a hairpin."""
from __future__ import annotations

import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.road import network
from sumo_avoid.road.polyline import SPUR_COS
from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario

pytestmark = pytest.mark.sumo
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
NODES = '<nodes><node id="W" x="-200" y="0"/><node id="M" x="0" y="0"/><node id="N" x="1" y="0"/><node id="E" x="200" y="0"/></nodes>'
# MN's lane 0 laid 15 m back: netconvert's internal lane into it turns back 11.8 m, the next one comes out again
HAIRPIN = ('<lane index="0" shape="-15.0,-4.8 -14.7,-4.8"/><lane index="1" shape="1.0,-1.6 1.3,-1.6"/>',
           '<connection from="WM" to="MN" fromLane="0" toLane="0"/><connection from="MN" to="NE" fromLane="0" toLane="0"/>')
# MN's lane 1 laid 12 m back and the way on only from it: the route changes lanes on a 0.2 m edge
LAID_APART = ('<lane index="0" shape="0.0,-4.8 0.3,-4.8"/><lane index="1" shape="-12.0,-1.6 -11.7,-1.6"/>',
              '<connection from="WM" to="MN" fromLane="0" toLane="0"/><connection from="MN" to="NE" fromLane="1" toLane="0"/>')
ROUTES = """<routes>
  <vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="20"/>
  <vehicle id="ego" type="ego_car" depart="0" departLane="0" departPos="100" departSpeed="10"><route edges="WM MN NE"/></vehicle>
</routes>"""


def _net(tmp_path, case) -> pathlib.Path:
    lanes, conns = case
    (tmp_path / "h.nod.xml").write_text(NODES)
    (tmp_path / "h.edg.xml").write_text(
        '<edges><edge id="WM" from="W" to="M" numLanes="2" speed="13.89"/>'
        f'<edge id="MN" from="M" to="N" numLanes="2" speed="13.89">{lanes}</edge>'
        '<edge id="NE" from="N" to="E" numLanes="1" speed="13.89"/></edges>')
    (tmp_path / "h.con.xml").write_text(f"<connections>{conns}</connections>")
    net = tmp_path / "h.net.xml"
    subprocess.run([str(BIN / "netconvert"), "-n", str(tmp_path / "h.nod.xml"), "-e", str(tmp_path / "h.edg.xml"),
                    "-x", str(tmp_path / "h.con.xml"), "--offset.disable-normalization", "true",
                    "--no-turnarounds", "true", "-o", str(net)], check=True, capture_output=True)
    return net


@pytest.mark.parametrize("case", [HAIRPIN, LAID_APART], ids=["hairpin", "laid_apart"])
def test_the_route_path_never_turns_back_on_itself(tmp_path, case):
    net = _net(tmp_path, case)
    road = network.Road.from_net_file(net)
    way_on = np.asarray(road._net.getLane(":N_0_0").getShape())
    assert way_on[0][0] < np.asarray(road._net.getLane("WM_0").getShape())[-1][0] - 4.0  # starts > 4 m behind the way in
    path = road.route(["WM", "MN", "NE"], depart_lane=0, vclass="passenger").path
    u = np.diff(path, axis=0)
    u /= np.hypot(*u.T)[:, None]
    assert (np.einsum("ij,ij->i", u[:-1], u[1:]) >= SPUR_COS).all()
    assert np.all(np.diff(path[:, 0]) > 0.0)  # east all the way


def _drive(tmp_path, case):
    _net(tmp_path, case)
    (tmp_path / "h.rou.xml").write_text(ROUTES)
    (tmp_path / "hook.toml").write_text('name = "hook"\n[sim]\nnet = "h.net.xml"\nroutes = ["h.rou.xml"]\n'
                                        'duration_s = 60.0\n[ego]\nids = ["ego"]\ncruise_speed_mps = 12.0\n')
    return outputs.run_metrics(runner.run(scenario.load(tmp_path / "hook.toml")))


def test_a_hairpin_inside_a_junction_is_driven_within_the_road(tmp_path):
    m = _drive(tmp_path, HAIRPIN)
    assert m["goal_reached"] and m["collisions"] == 0
    assert m["phi_wall"] == 0.0 and m["off_road_m"] == 0.0


def test_a_lane_change_on_an_edge_whose_lanes_are_laid_apart_does_not_stall(tmp_path):
    """From 100 m along WM at 10 m/s, 298 m to the goal at 12 m/s: about 25 s driving on (the path
    back round the 12 m spur stood the car at its hairpin, 38.5 s)."""
    m = _drive(tmp_path, LAID_APART)
    assert m["goal_reached"] and m["collisions"] == 0 and m["off_road_m"] == 0.0
    assert m["time_to_goal_s"] < 30.0
