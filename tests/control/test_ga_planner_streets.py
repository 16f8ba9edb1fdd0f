"""ga_planner on the streets library in real SUMO (issue 33: lane permissions; scenarios/streets/van_bike_lane,
a netconvert net): a delivery van stands in the only car lane from x 150 to 156.5, a bike lane and a sidewalk
beside it, the oncoming lane busy. The planner may plan only in the lanes a car may use: it waits behind the
van (it hit the van with ground truth, which did not show it standing vehicles on a road, and drove 242 m on
the bike lane into a cyclist with the radar)."""
import pytest
from conftest import run_scenario

pytestmark = pytest.mark.sumo


@pytest.mark.parametrize("sensor", ["truth", "radar"])
def test_the_planner_waits_behind_the_van_never_on_the_bike_lane(sensor):
    res, m = run_scenario("streets/van_bike_lane", seed=1,
                          overrides=["sim.duration_s=60", 'ego.controller="ga_planner"', f'ego.sensor="{sensor}"'])
    assert m["forbidden_lane_m"] == 0.0 and m["off_road_m"] == 0.0
    assert m["collisions"] == 0 and m["sumo_ego_collisions"] == 0 and m["vru_collisions"] == 0
    ego = res.traj[res.traj["id"] == "ego"]
    assert 120.0 < ego["x"].max() < 150.0 - 0.5 * ego["length"].iloc[0]  # up to the van, behind its rear
    assert ego[ego["time_s"] >= 50.0]["speed"].max() < 0.5  # and waiting there (12 m short: room to steer out)
