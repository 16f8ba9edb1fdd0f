"""Flocking on roads (issue 14 item 9): the carriageway (tests/road/test_carriageway.py) as the
flock's walls in the route frame, the braking-curve bounds, and a flock on a curved road built by netconvert."""
import math
import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.control.flocking.road_flock import course_limits, safety_caps
from sumo_avoid.control.flocking.terms import preset
from sumo_avoid.core.geometry import footprint_corners
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
P8 = preset("paper_v8", v_flock_mps=14.0, v_max_mps=20.0, shill_normal_only=True)


def _D(r, a, p):  # SPEC §1 braking curve, by hand
    return 0.0 if r <= 0 else (r * p if r * p < a / p else math.sqrt(2 * a * r - a * a / (p * p)))


def test_safety_caps_hand_values():
    a, g = P8.a_shill_mps2, P8.p_shill_ps  # 4.18, 8.12
    own = footprint_corners(np.array([[0.0, 0.0]]), np.zeros(1), np.array([4.0]), np.array([2.0]))[0]
    # 1.3 m to the right bound, 2.3 m to the left one, far from the route's end; nothing else
    v = safety_caps(np.array([15.0, -5.0]), own, np.array([1.3, 2.3, 500.0]), [], P8)
    assert v[0] == 15.0
    assert v[1] == pytest.approx(-_D(1.0, a, g))  # -sqrt(2*4.18*1.0 - (4.18/8.12)^2) = -2.84517
    assert v[1] == pytest.approx(-2.84517, abs=1e-5)
    # a car 12 m ahead (rear at s 14, front of the ego at 2) in the ego's strip, driving 10 m/s
    box = footprint_corners(np.array([[16.0, 0.5]]), np.zeros(1), np.array([4.0]), np.array([2.0]))
    v = safety_caps(np.array([25.0, 0.0]), own, np.array([1.3, 2.3, 500.0]), [(box, np.array([[10.0, 0.0]]))], P8)
    # sqrt(10^2 + D(12 - 2)^2) = sqrt(100 + 8.36*10 - 0.265) = 13.5401
    assert v[0] == pytest.approx(math.hypot(10.0, _D(12.0 - P8.road_gap_m, a, g)))
    assert v[0] == pytest.approx(13.5401, abs=1e-4)
    # the same car beside (s overlap), 1.0 m to the left, drifting towards the ego at 0.5 m/s: closing
    # speed at most D(1.0 - side_gap 0.5)
    box = footprint_corners(np.array([[1.0, 3.0]]), np.zeros(1), np.array([4.0]), np.array([2.0]))
    v = safety_caps(np.array([15.0, 3.0]), own, np.array([1.3, 2.3, 500.0]), [(box, np.array([[15.0, -0.5]]))], P8)
    assert v[0] == 15.0 and v[1] == pytest.approx(-0.5 + _D(1.0 - P8.side_gap_m, a, g))  # 1.4787
    # past the right bound (distance 0): never further out; the route's end 5 m ahead
    v = safety_caps(np.array([15.0, -1.0]), own, np.array([0.0, 3.0, 5.0]), [], P8)
    assert v[1] == 0.0 and v[0] == pytest.approx(_D(5.0 - P8.r0_shill_m, a, g))


def test_course_limits_hand_values():
    assert course_limits(np.array([10.0, 3.0]), P8) == pytest.approx([10.0, 1.5])
    assert course_limits(np.array([1.0, -3.0]), P8) == pytest.approx([1.0, -math.tan(math.radians(35.0))])
    assert course_limits(np.array([0.0, 2.0]), P8) == pytest.approx([0.0, 0.0])


@pytest.fixture(scope="module")
def curved_road(tmp_path_factory):
    """A 3-lane one-way road (3.5 m lanes): 80 m straight, a left bend of radius 100 m through 90
    degrees, 150 m straight, built by SUMO's netconvert."""
    d = tmp_path_factory.mktemp("flockroad")
    arc = [(80 + 100 * math.sin(t), 100 - 100 * math.cos(t)) for t in np.linspace(0, math.pi / 2, 19)]
    shape = " ".join(f"{x:.2f},{y:.2f}" for x, y in [(0, 0)] + arc + [(180, 250)])
    (d / "r.nod.xml").write_text('<nodes>\n  <node id="A" x="0" y="0"/>\n  <node id="B" x="180" y="250"/>\n</nodes>\n')
    (d / "r.edg.xml").write_text(f'<edges>\n  <edge id="r" from="A" to="B" numLanes="3" speed="33.33" width="3.5" '
                                 f'shape="{shape}"/>\n</edges>\n')
    subprocess.run([str(BIN / "netconvert"), "-n", str(d / "r.nod.xml"), "-e", str(d / "r.edg.xml"),
                    "-o", str(d / "curve.net.xml")], check=True, capture_output=True)
    egos = [("f0", 0, 30), ("f1", 1, 50), ("f2", 2, 70), ("f3", 1, 90)]
    (d / "flock.rou.xml").write_text(
        '<routes>\n  <vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="40"/>\n'
        '  <route id="r" edges="r"/>\n'
        + "".join(f'  <vehicle id="{v}" type="ego_car" route="r" depart="0" departLane="{lane}" departPos="{pos}" '
                  f'departSpeed="14" insertionChecks="none"/>\n' for v, lane, pos in egos)
        + "</routes>\n")
    (d / "flock.toml").write_text(
        'name = "curve_flock"\n[sim]\nnet = "curve.net.xml"\nroutes = ["flock.rou.xml"]\nstep_s = 0.1\n'
        'duration_s = 18.0\nseed = 1\n[ego]\nids = ["f0", "f1", "f2", "f3"]\ncontroller = "flocking"\n'
        '[actuators.kinematic]\nmax_accel_mps2 = 3.0\nmax_decel_mps2 = 8.0\nmax_lat_accel_mps2 = 4.0\n'
        'max_yaw_rate_radps = 0.8\nmin_turn_radius_m = 5.5\nmax_reverse_speed_mps = 0.0\n'
        '[controllers.flocking]\npreset = "paper_v8"\nv_flock_mps = 14.0\nv_max_mps = 20.0\nspeed_rule = "cutoff"\n'
        'shill_normal_only = true\n')
    return d


@pytest.mark.sumo
def test_a_flock_stays_on_a_curved_road_and_follows_the_bend(curved_road):
    res = runner.run(scenario.load(curved_road / "flock.toml"))
    ego = res.traj[res.traj["is_ego"] == 1]
    corners = footprint_corners(ego[["x", "y"]].to_numpy(), ego["heading"].to_numpy(),
                                ego["length"].to_numpy(), ego["width"].to_numpy())
    out = res.scene.road.footprint_outside_distance(corners)
    assert out.max() <= 0.1  # no footprint more than 0.1 m past the road's edge, ever
    last = ego.groupby("id").tail(1)
    # every member went through the bend (heading turned by ~90 degrees, north) and kept moving
    assert (np.abs(last["heading"].to_numpy() - math.pi / 2) < 0.15).all()
    assert (last["y"].to_numpy() > 80.0).all() and (last["speed"].to_numpy() > 8.0).all()
