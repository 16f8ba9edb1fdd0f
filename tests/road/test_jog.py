"""A road that steps sideways at a point (issue 34: lane shapes OSM-derived nets really have): Berlin's
Doerpfeldstrasse joins two car lanes 1.57 m apart by a 1.6 m internal lane at right angles to both
(clusterJ1_J2), a tram lane on the left, a bike lane on the right. The route's path crosses the step on a
ramp (:func:`sumo_avoid.road.polyline.ease_jogs`) and APF-SA drives it within the road; hand values for
the ramp, a netconvert net of the same step for the drive."""
from __future__ import annotations

import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.road import network
from sumo_avoid.road.polyline import JOG_SLOPE, ease_jogs
from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"


def test_a_step_aside_becomes_a_ramp_centred_on_it():
    """1.4 m across at x = 30: the ramp needs 1.4 / 0.05 = 28 m, 14 m on either side of the step, through the
    step's midpoint, which stands for the step's first vertex (a stop line there stays at the step)."""
    assert JOG_SLOPE == 0.05
    out, where = ease_jogs(np.array([[0.0, 0.0], [30.0, 0.0], [30.0, 1.4], [60.0, 1.4]]))
    assert np.allclose(out, [[0.0, 0.0], [16.0, 0.0], [30.0, 0.7], [44.0, 1.4], [60.0, 1.4]])
    assert where.tolist() == [0, 2, 3, 4]


def test_a_step_over_several_vertices_drops_the_ones_between():
    """(30, 0) -> (30.5, 0.7) -> (31, 1.4): 1.4 m across, 1 m ahead; the ramp needs 28 - 1 = 27 m more,
    13.5 m on either side; the middle vertex goes (the midpoint stands for it too)."""
    out, where = ease_jogs(np.array([[0.0, 0.0], [30.0, 0.0], [30.5, 0.7], [31.0, 1.4], [60.0, 1.4]]))
    assert np.allclose(out, [[0.0, 0.0], [16.5, 0.0], [30.5, 0.7], [44.5, 1.4], [60.0, 1.4]])
    assert where.tolist() == [0, 2, 2, 3, 4]


def test_a_short_step_is_eased_within_half_its_neighbours():
    """Segments of 4 m before and after: each end of the ramp lies at most 2 m from the step."""
    out, where = ease_jogs(np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.4], [8.0, 1.4]]))
    assert np.allclose(out, [[0.0, 0.0], [2.0, 0.0], [4.0, 0.7], [6.0, 1.4], [8.0, 1.4]])
    assert where.tolist() == [0, 2, 3, 4]


@pytest.mark.parametrize("pts", [
    [[0.0, 0.0], [30.0, 0.0], [60.0, 3.2], [90.0, 3.2]],  # a lane change blended over 30 m: beyond a step's 4 m of line
    [[0.0, 0.0], [30.0, 0.0], [33.0, 1.0], [35.0, 4.0], [35.0, 30.0]],  # a right-angle turn: no way on parallel
    [[0.0, 0.0], [30.0, 0.0], [30.0, 0.1], [60.0, 0.1]],  # 0.1 m across: a kink, not a step
    [[0.0, 0.0], [30.0, 0.0], [30.0, 5.0], [60.0, 5.0]],  # 5 m across: beyond a step's reach (4 m of line)
    # a roundabout's ring polygon into its exit (scenarios/roads/roundabout1, rEN_0 -> N_out_0): 0.25 m across
    # the way in over 2.2 m, a bend, not a step (flatter than 20 degrees)
    [[10.88, 18.84], [9.19, 19.72], [7.44, 20.44], [7.12, 20.54], [4.77, 21.59], [3.09, 23.02]],
])
def test_lane_changes_turns_kinks_and_wide_offsets_are_kept(pts):
    out, where = ease_jogs(np.array(pts))
    assert np.array_equal(out, np.array(pts)) and where.tolist() == list(range(len(pts)))


EDGES = """<edges>
 <edge id="WM" from="W" to="M" numLanes="3" speed="13.89" shape="-200,0 0,0">
  <lane index="0" allow="bicycle" width="2.0"/><lane index="1" width="3.2"/><lane index="2" allow="tram" width="3.2"/></edge>
 <edge id="ME" from="M" to="E" numLanes="3" speed="13.89" shape="0,1.6 200,1.6">
  <lane index="0" allow="bicycle" width="2.0"/><lane index="1" width="3.2"/><lane index="2" allow="tram" width="3.2"/></edge>
</edges>"""


def _net(tmp_path) -> pathlib.Path:
    (tmp_path / "j.nod.xml").write_text('<nodes><node id="W" x="-200" y="0"/><node id="M" x="0" y="0"/>'
                                        '<node id="E" x="200" y="0"/></nodes>')
    (tmp_path / "j.edg.xml").write_text(EDGES)
    net = tmp_path / "j.net.xml"
    subprocess.run([str(BIN / "netconvert"), "-n", str(tmp_path / "j.nod.xml"), "-e", str(tmp_path / "j.edg.xml"),
                    "--offset.disable-normalization", "true", "--no-turnarounds", "true", "-o", str(net)],
                   check=True, capture_output=True)
    return net


@pytest.mark.sumo
def test_the_car_lane_steps_aside_at_right_angles_and_the_path_ramps(tmp_path):
    road = network.Road.from_net_file(_net(tmp_path))
    step = np.asarray(road._net.getLane(":M_0_1").getShape())
    assert np.allclose(step, [[0.0, -4.8], [0.0, -3.2]])  # netconvert's internal lane: 1.6 m straight across
    plan = road.route(["WM", "ME"], depart_lane=1, vclass="passenger")
    u = np.diff(plan.path, axis=0)
    assert np.all(u[:, 0] > 0.0) and np.abs(u[:, 1] / u[:, 0]).max() <= JOG_SLOPE + 1e-9
    (link,) = plan.links
    assert abs(link.s_stop_m - 200.0) < 0.05  # the junction's line stays at the step, 200 m along WM


@pytest.mark.sumo
def test_apf_sa_drives_over_the_step_within_the_road(tmp_path):
    """At cruise speed past the step, a tram lane on the left and a bike lane on the right. No footprint stays
    inside the car lanes at the step itself (a 1.8 m car across two 3.2 m lanes 1.6 m apart sticks out 0.09 m at
    the least); over the ramp phi_wall (the mean over the steps out) is 0.055 m. Without the ramp the car slowed
    to 2.7 m/s at the step, swung 0.93 m into the tram lane and was out for 3.3 s (phi_wall 0.64 m)."""
    _net(tmp_path)
    (tmp_path / "j.rou.xml").write_text(
        '<routes><vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="20"/>'
        '<vehicle id="ego" type="ego_car" depart="0" departLane="1" departPos="100" departSpeed="10">'
        '<route edges="WM ME"/></vehicle></routes>')
    (tmp_path / "jog.toml").write_text('name = "jog"\n[sim]\nnet = "j.net.xml"\nroutes = ["j.rou.xml"]\n'
                                       'duration_s = 40.0\n[ego]\nids = ["ego"]\ncruise_speed_mps = 13.0\n')
    m = outputs.run_metrics(runner.run(scenario.load(tmp_path / "jog.toml")))
    assert m["goal_reached"] and m["collisions"] == 0 and m["off_road_m"] == 0.0
    assert m["forbidden_lane_m"] == 0.0
    assert m["phi_wall"] <= 0.1


BERLIN = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "cities" / "berlin_doerpfeldstr" / "net.net.xml.gz"


@pytest.mark.skipif(not BERLIN.exists(), reason="../shared/cities is not beside the project")
def test_berlin_doerpfeldstrasse_step_is_a_ramp_and_its_junction_line_stays():
    """-45875465_1 (49.34 m) -> :clusterJ1_J2_2_0 (1.60 m, at right angles) -> -45875465.50_1: the path turns by
    at most atan(0.05) and 1 mrad anywhere (the two lanes are 0.1 mrad off parallel), and the junction's stop line (a signalised junction; the car's link has no signal of its own) lies where
    the car lane ends, 49.34 m along."""
    road = network.Road.from_net_file(BERLIN)
    plan = road.route(["-45875465", "-45875465.50"], depart_lane=1, vclass="passenger")
    u = np.diff(plan.path, axis=0)
    h = np.arctan2(u[:, 1], u[:, 0])
    assert np.abs(np.diff(h)).max() <= np.arctan(JOG_SLOPE) + 1e-3
    (link,) = plan.links
    assert link.junction == "clusterJ1_J2" and abs(link.s_stop_m - 49.34) < 0.05
