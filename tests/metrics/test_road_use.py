"""wrong_way_m and off_road_m (sumo_avoid.metrics.road_use) on hand-built recordings on the real
left_turn net, with hand-computed values, and on a real run checked against an independent count."""
import math

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, run_scenario

from sumo_avoid.metrics.road_use import road_use
from sumo_avoid.rollout.result import RunResult, Scene
from sumo_avoid.sumo.road import Road

# left_turn: crossroads at (0, 0), 2 lanes of 3.5 m per direction, right-hand traffic: S2C runs
# north at x = 1.75 and 5.25, C2S south at x = -1.75 and -5.25; road edges at x = +-7; the
# junction shape spans |x|, |y| <= 11


def path(vid, xs, ys, heading, ego=True):
    return [{"step": k, "time_s": 0.1 * k, "id": vid, "is_ego": ego, "x": float(x), "y": float(y), "vx": 0.0, "vy": 0.0, "speed": 0.0,
                 "heading": heading, "length": 4.0, "width": 2.0} for k, (x, y) in enumerate(zip(xs, ys))]


def result(rows, net="left_turn"):
    road = Road.from_net_file(ROOT / "nets" / f"{net}.net.xml")
    return RunResult(None, Scene(road), pd.DataFrame(rows), None, {}, 0, 0.0, {})


def test_hand_built_recording_on_the_left_turn_net():
    north = math.pi / 2
    up = np.arange(-120.0, -59.0)  # 60 segments of 1 m
    rows = (path("wrong", np.full(61, -1.75), up, north)  # northbound in C2S: 60 m against
            + path("right", np.full(61, 1.75), up, north)  # northbound in S2C: 0
            + path("backing", np.full(61, 5.25), up[::-1], north)  # heading north, moving south in S2C: 60 m
            + path("field", np.full(61, 30.0), up, north)  # 23 m east of the road: 60 m off road
            + path("junction", np.full(7, -1.75), np.arange(-3.0, 4.0), north)  # inside the junction: 0
            # eastwards (a little north) from x = 3 to 13 across S2C at y ~ -100: midpoints 3.5 .. 12.5,
            # those at 7.5 .. 12.5 beyond the edge at 7: 6 segments off the road; 90 - 5.7 degrees
            # from the lanes' direction: not against them
            + path("out", np.arange(3.0, 14.0), -100.0 + 0.1 * np.arange(11), 0.1)
            + path("other", np.full(61, -1.75), up, north, ego=False))  # not an ego: not counted
    m = road_use(result(rows))
    out_len = 6 * math.hypot(1.0, 0.1)
    assert m["wrong_way_m"] == pytest.approx(120.0)
    assert m["off_road_m"] == pytest.approx(60.0 + out_len)


def test_no_ego_moved():
    rows = path("still", np.zeros(5), np.full(5, -100.0), 0.0)
    assert road_use(result(rows)) == {"wrong_way_m": 0.0, "off_road_m": 0.0}


def test_real_run_a_blind_ego_turning_back_on_a_one_way_road():
    """The scripted ego is told to drive west on the one-way (eastbound) overtaking road: it turns
    round (leaving the road on the way) and comes back against the lanes. Checked against an
    independent count: the road is the band 0 <= x <= 1500, -14 <= y <= 0 without junctions inside,
    every lane runs east, so a segment is against a lane where it moves west with its midpoint in
    that band, and off the road where the midpoint is outside it."""
    res, m = run_scenario("crash_straight", overrides=["controllers.scripted.direction_deg=180", "sim.duration_s=30"])
    e = res.traj[res.traj["is_ego"]].sort_values("step")
    p = e[["x", "y"]].to_numpy()
    d = np.diff(p, axis=0)
    mid = 0.5 * (p[1:] + p[:-1])
    length = np.hypot(d[:, 0], d[:, 1])
    inside = (mid[:, 0] > 0) & (mid[:, 0] < 1500) & (mid[:, 1] > -14.0) & (mid[:, 1] < 0.0)
    assert m["wrong_way_m"] > 10.0 and m["off_road_m"] > 10.0
    assert m["wrong_way_m"] == pytest.approx(length[inside & (d[:, 0] < 0)].sum(), abs=0.5)
    assert m["off_road_m"] == pytest.approx(length[~inside].sum(), abs=0.5)
