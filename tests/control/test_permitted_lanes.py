"""Lane permissions on real SUMO (a street netconvert builds here): a delivery van stands in the only
car lane, a bike lane (bicycles only) and a sidewalk beside it, the oncoming lane busy. The only way
past is the bike lane, which a car may not use: APF-SA waits behind the van (SPEC §6)."""
from __future__ import annotations

import pathlib
import subprocess

import pytest
import sumo

from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario

pytestmark = pytest.mark.sumo
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
EDGES = """<edges>
  <edge id="WE" from="W" to="E" numLanes="3" speed="13.89">
    <lane index="0" allow="pedestrian" width="2.0"/><lane index="1" allow="bicycle" width="1.5"/><lane index="2" width="3.2"/>
  </edge>
  <edge id="EW" from="E" to="W" numLanes="2" speed="13.89">
    <lane index="0" allow="pedestrian" width="2.0"/><lane index="1" width="3.2"/>
  </edge>
</edges>"""
ROUTES = """<routes>
  <vType id="ego_car" length="4.5" width="1.8" accel="3" decel="8" maxSpeed="20"/>
  <vType id="van" vClass="delivery" length="6.5" width="2.1"/>
  <vType id="car" length="4.5" width="1.8" maxSpeed="14"/>
  <vType id="bike" vClass="bicycle" length="1.6" width="0.65" maxSpeed="5"/>
  <vehicle id="van" type="van" depart="0" departPos="150" departLane="2" departSpeed="0">
    <route edges="WE"/><stop lane="WE_2" endPos="156.5" duration="1000" parking="false"/>
  </vehicle>
  <flow id="oncoming" type="car" begin="0" end="200" period="5" departLane="1" departSpeed="max"><route edges="EW"/></flow>
  <flow id="cyclists" type="bike" begin="0" end="200" period="25" departLane="1"><route edges="WE"/></flow>
  <vehicle id="ego" type="ego_car" depart="2" departLane="2" departSpeed="10"><route edges="WE"/></vehicle>
</routes>"""


def test_the_ego_waits_behind_a_van_rather_than_pass_on_the_bike_lane(tmp_path):
    (tmp_path / "v.nod.xml").write_text('<nodes><node id="W" x="-300" y="0"/><node id="E" x="300" y="0"/></nodes>')
    (tmp_path / "v.edg.xml").write_text(EDGES)
    subprocess.run([str(BIN / "netconvert"), "-n", str(tmp_path / "v.nod.xml"), "-e", str(tmp_path / "v.edg.xml"),
                    "--offset.disable-normalization", "true", "--no-turnarounds", "true", "-o",
                    str(tmp_path / "v.net.xml")], check=True, capture_output=True)
    (tmp_path / "v.rou.xml").write_text(ROUTES)
    (tmp_path / "van.toml").write_text('name = "van"\n[sim]\nnet = "v.net.xml"\nroutes = ["v.rou.xml"]\n'
                                       'duration_s = 60.0\n[ego]\nids = ["ego"]\ncruise_speed_mps = 12.0\n')
    res = runner.run(scenario.load(tmp_path / "van.toml"))
    m = outputs.run_metrics(res)
    assert m["collisions"] == 0 and m["vru_collisions"] == 0 and m["sumo_collisions"] == 0
    assert m["forbidden_lane_m"] == 0.0 and m["off_road_m"] == 0.0 and m["phi_wall"] == 0.0
    ego = res.traj[res.traj["id"] == "ego"]
    # the car lane spans y in [-3.2, 0] (the bike lane below it): the ego's footprint stays in it
    assert ego["y"].between(-3.2 + 0.9 - 0.05, -0.9 + 0.05).all()
    assert ego["x"].max() < -150.0 - 2.25  # behind the van (its rear at x = -300 + 156.5 - 6.5 = -150 m)
    assert (ego["speed"] < 0.1).sum() > 100  # it waited
