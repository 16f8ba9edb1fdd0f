"""Bridges and tunnels (core.levels): a car on a bridge passing right over the ego is no obstacle for
the sensors and controllers and no collision, gap or TTC pair for the metrics; the same car on the
ego's level still is. The net is built here by netconvert from tests/data/levels (a road 8 m over
another, crossing it without a junction); the flat variant is the same net with every z removed."""
import numpy as np
import pandas as pd
import pytest

from sumo_avoid.core.levels import LEVELS, has_levels, same_level
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import Observation
from sumo_avoid.metrics import basic, vru
from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.sensing.perception import obstacle_vehicles
from tests.conftest import netconvert

CRUISE_MPS = 10.0
# the ego's front reaches the crossing (251.6, 248.4) 15 s after it departs on "low", and so does the
# car's on the bridge (ramp_up 200.16 m + 48.4 m on "up"): both at 10 m/s
ROUTES = """<routes>
  <vType id="car" length="4.5" width="1.8" accel="2.6" decel="4.5" maxSpeed="10"/>
  <vehicle id="ego" type="car" depart="0" departPos="101.6" departSpeed="10"><route edges="low"/></vehicle>
  <vehicle id="over" type="car" depart="0" departPos="98.6" departSpeed="10"><route edges="ramp_up up ramp_down"/></vehicle>
</routes>
"""


def test_levels_by_hand():
    assert LEVELS.clearance_m == 4.0
    assert same_level([0.0, 0.0, 3.9], [4.0, 4.1, 8.0]).tolist() == [True, False, False]
    assert not has_levels([0.0, 3.0, 4.0]) and has_levels([0.0, 8.0]) and not has_levels([])
    # the snapshot's test for one row; ground truth for a controller leaves the bridge out
    snap = Snapshot(0.0, ("ego", "over", "beside"), [[0, 0], [0, 0.5], [6, 0]], np.zeros((3, 2)), np.zeros(3),
                    np.full(3, 4.5), np.full(3, 1.8), [True, False, False], z=[0.0, 8.0, 0.3])
    assert snap.levels and snap.same_level(0).tolist() == [True, False, True]
    obs = Observation(snap, ("ego",), np.array([0]), np.zeros(1))
    pos = obstacle_vehicles(obs, 0, snap.pos[0], 50.0)[0]
    assert pos.tolist() == [[6.0, 0.0]]
    flat = Snapshot(0.0, snap.ids, snap.pos, snap.vel, snap.heading, snap.length, snap.width, snap.is_ego)
    assert not flat.levels and flat.z.tolist() == [0.0, 0.0, 0.0]
    assert len(obstacle_vehicles(Observation(flat, ("ego",), np.array([0]), np.zeros(1)), 0, flat.pos[0], 50.0)[0]) == 2


def test_the_vru_metrics_pair_only_road_users_on_one_level():
    """A person and a cyclist on a bridge right over the ego: no pair; the same on its level: contacts."""
    ego = dict(step=[0], time_s=[0.0], id=["ego"], is_ego=[True], x=[0.0], y=[0.0], heading=[0.0], length=[4.5],
               width=[1.8])
    bike = dict(step=[0], time_s=[0.0], id=["bike"], is_ego=[False], x=[1.0], y=[0.0], heading=[0.0], length=[1.6],
                width=[0.6])
    person = pd.DataFrame(dict(step=[0], time_s=[0.0], id=["p"], x=[0.5], y=[0.0], length=[0.2], width=[0.5]))
    for z, pairs in ((8.0, 0), (0.5, 1)):
        traj = pd.concat([pd.DataFrame({**ego, "z": [0.0]}), pd.DataFrame({**bike, "z": [z]})], ignore_index=True)
        assert len(vru.ego_person_pairs(traj, person.assign(z=[z]))) == pairs
        assert len(vru.cyclist_gaps(traj, {"bike": "bicycle"})) == pairs


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("levels")
    netconvert("levels", d, "levels")
    (d / "flat").mkdir()
    netconvert("levels", d / "flat", "levels", "--flatten", "true")
    (d / "r.rou.xml").write_text(ROUTES)
    out = {}
    for name, net, sensor in (("bridge", "levels.net.xml", "truth"), ("bridge_radar", "levels.net.xml", "radar"),
                              ("flat", "flat/levels.net.xml", "truth")):
        f = d / f"{name}.toml"
        f.write_text(f'name = "{name}"\n[sim]\nnet = "{net}"\nroutes = ["r.rou.xml"]\nstep_s = 0.1\nduration_s = 42.0\n'
                     f'seed = 1\n[ego]\nids = ["ego"]\ncontroller = "apf_sa"\nsensor = "{sensor}"\n'
                     f'cruise_speed_mps = {CRUISE_MPS}\n[sensors.radar]\nlog_detections = true\n')
        res = runner.run(scenario.load(f))
        out[name] = (res, outputs.run_metrics(res))
    return out


def _at_crossing(res):
    """The ego's and the car's rows of the step they are closest, and that distance (m)."""
    t = res.traj
    m = t[t["id"] == "ego"].merge(t[t["id"] == "over"], on="step", suffixes=("_e", "_o"))
    d = np.hypot(m["x_e"] - m["x_o"], m["y_e"] - m["y_o"])
    return m.loc[d.idxmin()], float(d.min())


def _slowest_passing(res, row) -> float:
    """The ego's lowest speed until 5 s after the crossing (later it slows for its goal), m/s."""
    ego = res.traj[res.traj["id"] == "ego"]
    return float(ego.loc[ego["time_s"] <= row["time_s_e"] + 5.0, "speed"].min())


@pytest.mark.sumo
def test_a_car_on_the_bridge_over_the_ego_is_no_obstacle_and_no_collision(runs):
    for name in ("bridge", "bridge_radar"):
        res, m = runs[name]
        row, d = _at_crossing(res)
        assert d < 1.0  # it passes right over the ego, footprints overlapping in x, y
        assert row["z_o"] == pytest.approx(8.0) and row["z_e"] == pytest.approx(0.0)  # SUMO's heights, recorded
        assert m["collisions"] == 0 and m["sumo_collisions"] == 0 and m["goal_reached"]
        assert m["min_ttc2d_s"] == 10.0 and m["min_gap_m"] > 50.0  # no pair with it at the crossing
        assert _slowest_passing(res, row) >= CRUISE_MPS - 1e-6  # never braked for it
    det = runs["bridge_radar"][0].tables["detections"]
    assert "over" not in set(det["target"])  # the radar does not see through the deck


@pytest.mark.sumo
def test_a_flat_net_keeps_two_levels_where_edges_cross_without_a_junction(runs):
    # every z removed (an OSM import without --osm.layer-elevation, or one whose heights put the road under a
    # bridge 0.66 m below it): the two edges still cross without a junction, so SUMO lets the cars pass through
    # each other, and so do the sensors, the controller and the metrics (road.grade)
    res, m = runs["flat"]
    row, d = _at_crossing(res)
    assert "z" not in res.traj and d < 1.0  # a flat net's recording has no z column; it passes right over the ego
    assert res.road.apart == {"low": frozenset({"up"}), "up": frozenset({"low"})}
    assert _slowest_passing(res, row) >= CRUISE_MPS - 1e-6 and m["collisions"] == 0 and m["min_gap_m"] > 50.0


@pytest.mark.sumo
def test_the_same_car_on_the_egos_level_still_counts(runs):
    # the recordings without heights and without the net's crossings: the crossing is a contact
    bridge, flat = runs["bridge"][0].traj, runs["flat"][0].traj
    assert len(basic.collision_events(bridge)) == 0
    assert len(basic.collision_events(bridge.drop(columns="z"))) == 1
    assert len(basic.collision_events(flat)) == 1


def test_edges_crossing_without_a_junction_by_hand():
    from sumo_avoid.core.levels import apart_mask, apart_pairs, part_of
    assert [part_of(x) for x in ("E_0", "-16652218_2", ":J_3_0", ":cluster_1_2_w0_0", ":J_c1_0", "")] == \
        ["E", "-16652218", ":J", ":cluster_1_2", ":J", ""]
    apart = {"low": frozenset({"up"}), "up": frozenset({"low"})}
    assert apart_mask(apart, "low_0", ["up_1", "low_1", ":J_0_0", ""]).tolist() == [True, False, False, False]
    assert apart_pairs(apart, ["low_0", "low_0", "up_0", "x_0"], ["up_0", "ramp_0", "low_1", "up_0"]).tolist() == \
        [True, False, True, False]
    # the snapshot's test: the car on "up" is on another level though all heights are 0; the one on "low" is not
    snap = Snapshot(0.0, ("ego", "over", "behind"), [[0, 0], [0, 0.5], [-6, 0]], np.zeros((3, 2)), np.zeros(3),
                    np.full(3, 4.5), np.full(3, 1.8), [True, False, False], lane=("low_0", "up_0", "low_0"), apart=apart)
    assert snap.levels and snap.same_level(0).tolist() == [True, False, True]
