"""ga_planner on a road in real SUMO (scenarios/planner/road.toml, a netconvert net): the first
12 s of the ego's drive, past the right lane's three stopped vehicles (e1 is straight along
y = 0 .. -10.5, lanes 3.5 m: lane 0 y -10.5 .. -7, the stopped vehicles at x ~120 .. 147)."""
import numpy as np
import pytest
from conftest import run_scenario

from sumo_avoid.plots.planner import parse_path

pytestmark = pytest.mark.sumo


@pytest.fixture(scope="module")
def road_run():
    return run_scenario("planner/road", seed=1, overrides=["sim.duration_s=32"])


def _dense(path, step_m=0.5):
    seg = np.diff(path, axis=0)
    n = np.maximum(1, np.ceil(np.hypot(*seg.T) / step_m).astype(int))
    return np.concatenate([a + np.linspace(0, 1, k, endpoint=False)[:, None] * d for a, d, k in zip(path, seg, n)]
                          + [path[-1:]])


def test_road_plans_stay_in_the_corridor_and_out_of_the_blocked_lane(road_run):
    res, m = road_run
    plans = res.tables["plans"]
    assert {"takeover", "horizon"} <= set(plans["trigger"])  # replanned as the horizon moves on
    usable = plans[plans["usable"]]
    assert len(usable) >= 0.8 * len(plans)
    beside = 0
    for row in usable.itertuples():
        p = _dense(parse_path(row.path))
        on_e1 = p[p[:, 0] < 195.0]
        # inside the road, the lane bounds 1.6 m away (waypoints 1.8 m, segments between them)
        assert (on_e1[:, 1] >= -10.5 + 1.6 - 1e-6).all() and (on_e1[:, 1] <= -1.6 + 1e-6).all()
        near = p[(p[:, 0] > 117.0) & (p[:, 0] < 150.0)]
        if row.time_s > 27.0 and len(near):  # the stopped vehicles known (seen from ~80 m): their lane blocked
            beside += 1
            assert (near[:, 1] >= -7.0 + 1.4 - 1e-6).all()
    assert beside >= 3
    ego = res.traj[res.traj["id"] == "ego"]
    past = ego[(ego["x"] > 117.0) & (ego["x"] < 150.0)]
    assert len(past) and (past["y"] - 0.5 * past["width"] > -7.0).all()  # drove past in lane 1
    assert m["collisions"] == 0 and m["phi_wall"] == 0.0
