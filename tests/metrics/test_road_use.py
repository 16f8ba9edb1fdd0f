"""wrong_way_m, off_road_m and reverse_m (sumo_avoid.metrics.road_use) on hand-built recordings on the real
left_turn net, with hand-computed values, and on a real run checked against an independent count."""
import math

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, run_scenario

from sumo_avoid.metrics.road_use import road_use
from sumo_avoid.rollout.result import RunResult, Scene
from sumo_avoid.road.network import Road

# left_turn: crossroads at (0, 0), 2 lanes of 3.5 m per direction, right-hand traffic: S2C runs
# north at x = 1.75 and 5.25, C2S south at x = -1.75 and -5.25; road edges at x = +-7; the
# junction shape spans |x|, |y| <= 11


def path(vid, xs, ys, heading, ego=True, speed=0.0):
    return [{"step": k, "time_s": 0.1 * k, "id": vid, "is_ego": ego, "x": float(x), "y": float(y), "vx": 0.0, "vy": 0.0, "speed": speed,
                 "heading": heading, "length": 4.0, "width": 2.0} for k, (x, y) in enumerate(zip(xs, ys))]


def result(rows, net="left_turn"):
    road = Road.from_net_file(ROOT / "nets" / f"{net}.net.xml")
    return RunResult(None, Scene(road), pd.DataFrame(rows), None, {}, 0, 0.0, {})


def test_hand_built_recording_on_the_left_turn_net():
    north = math.pi / 2
    up = np.arange(-120.0, -59.0)  # 60 segments of 1 m
    rows = (path("wrong", np.full(61, -1.75), up, north)  # northbound in C2S: 60 m against
            + path("right", np.full(61, 1.75), up, north)  # northbound in S2C: 0
            + path("backing", np.full(61, 5.25), up[::-1], north)  # heading north, backing south in S2C: 60 m reversing, not against
            + path("ghost_backing", np.full(61, -5.25), up, -north)  # heading south, backing north in C2S: 60 m reversing, not against
            + path("field", np.full(61, 30.0), up, north)  # 23 m east of the road: 60 m off road
            + path("junction", np.full(7, -1.75), np.arange(-3.0, 4.0), north)  # inside the junction: 0
            # eastwards (a little north) from x = 3 to 13 across S2C at y ~ -100: midpoints 3.5 .. 12.5,
            # those at 7.5 .. 12.5 beyond the edge at 7: 6 segments off the road; 90 - 5.7 degrees
            # from the lanes' direction: not against them
            + path("out", np.arange(3.0, 14.0), -100.0 + 0.1 * np.arange(11), 0.1)
            + path("other", np.full(61, -1.75), up, north, ego=False))  # not an ego: not counted
    m = road_use(result(rows))
    out_len = 6 * math.hypot(1.0, 0.1)
    assert m["wrong_way_m"] == pytest.approx(60.0)
    assert m["off_road_m"] == pytest.approx(60.0 + out_len)
    assert m["reverse_m"] == pytest.approx(120.0)


def test_a_car_facing_the_traffic_is_against_it_whichever_way_it_moves():
    north = math.pi / 2
    up = np.arange(-120.0, -89.0)  # 30 segments of 1 m
    # heading north in the southbound C2S lane, backing south (with the lane's traffic)
    m = road_use(result(path("facing", np.full(31, -1.75), up[::-1], north)))
    assert m["wrong_way_m"] == pytest.approx(30.0)
    assert m["reverse_m"] == pytest.approx(30.0)


def test_no_ego_moved():
    rows = path("still", np.zeros(5), np.full(5, -100.0), 0.0)
    assert road_use(result(rows)) == {"wrong_way_m": 0.0, "off_road_m": 0.0, "reverse_m": 0.0, "forbidden_lane_m": 0.0,
                                      "speeding_m": 0.0}


def test_speeding_is_more_than_1_kmh_over_the_limit_of_the_lane_outside_junctions():
    # left_turn's lanes allow 13.89 m/s; speeding is above 13.89 + 1/3.6 = 14.168 m/s
    north = math.pi / 2
    up = np.arange(-120.0, -59.0)  # 60 segments of 1 m in S2C
    rows = (path("fast", np.full(61, 1.75), up, north, speed=15.0)  # 60 m over the limit
            + path("at_limit", np.full(61, 5.25), up, north, speed=14.1)  # 0.21 m/s over: within the tolerance
            + path("junction", np.full(7, 1.75), np.arange(-3.0, 4.0), north, speed=20.0)  # no limit there: 0
            + path("field", np.full(61, 30.0), up, north, speed=30.0)  # off every lane: 0 (it is off_road_m)
            + path("other", np.full(61, -1.75), up, -north, ego=False, speed=30.0))  # not an ego
    assert road_use(result(rows))["speeding_m"] == pytest.approx(60.0)


def test_real_run_a_blind_ego_backing_up_a_one_way_road():
    """The scripted ego is told to drive west on the one-way (eastbound) overtaking road: it swings
    its nose a little, stops, and backs up westwards (the actuator reverses towards a wish behind
    it), out of the road at x = 0. Checked against an independent count: the road is the band
    0 <= x <= 1500, -14 <= y <= 0 without junctions inside, every lane runs east, so a segment is
    against a lane where the car faces west (cos heading < 0) with its midpoint in that band, backing
    up where it moves against its heading, off the road where the midpoint is outside the band.
    The recorded velocity of a backing ego points backwards (SUMO reports |v|; sim.read signs it)."""
    res, m = run_scenario("crash_straight", overrides=["controllers.scripted.direction_deg=180", "sim.duration_s=30"])
    e = res.traj[res.traj["is_ego"]].sort_values("step")
    p = e[["x", "y"]].to_numpy()
    h = e["heading"].to_numpy()[:-1]
    d = np.diff(p, axis=0)
    mid = 0.5 * (p[1:] + p[:-1])
    length = np.hypot(d[:, 0], d[:, 1])
    inside = (mid[:, 0] > 0) & (mid[:, 0] < 1500) & (mid[:, 1] > -14.0) & (mid[:, 1] < 0.0)
    backing = d[:, 0] * np.cos(h) + d[:, 1] * np.sin(h) < 0
    assert m["reverse_m"] > 10.0 and m["off_road_m"] > 10.0
    assert m["wrong_way_m"] == pytest.approx(length[inside & (np.cos(h) < 0)].sum(), abs=0.5)
    assert m["reverse_m"] == pytest.approx(length[backing].sum(), abs=0.5)
    assert m["off_road_m"] == pytest.approx(length[~inside].sum(), abs=0.5)
    moving_west = e[(e["x"].diff().shift(-1) < -0.1) & (e["x"] > 5.0)]  # (off the net SUMO says 0 m/s)
    assert len(moving_west) > 50 and (moving_west["vx"] < 0).mean() > 0.9


def test_a_car_in_its_lane_under_a_tram_track_is_on_no_forbidden_lane(tmp_path):
    # netconvert lays a street (bike lane street_0, car lane street_1) and a tram track the other way over
    # the car lane (Braunschweig's net has such tracks). A car driving east along the track's centre line
    # is in its car lane and on the track (whose centre line is the nearer): not on a forbidden lane, not
    # against the traffic; along the bike lane's centre it is on a forbidden lane (not as a bicycle)
    import sumolib
    from conftest import netconvert

    from sumo_avoid.metrics.road_use import forbidden

    net_file = netconvert("tram_street", tmp_path, "tram_street")
    net = sumolib.net.readNet(str(net_file))
    y = {k: net.getLane(k).getShape()[0][1] for k in ("street_0", "street_1", "tram_0")}
    assert abs(y["tram_0"] - y["street_1"]) < 0.5 * net.getLane("street_1").getWidth()  # the track runs in the car lane
    road = Road.from_net_file(net_file)
    xs = np.arange(50.0, 151.0)
    on_track = np.column_stack([xs, np.full(len(xs), y["tram_0"])])
    in_bike_lane = np.column_stack([xs, np.full(len(xs), y["street_0"])])
    cars = np.full(len(xs), "passenger", dtype=object)
    assert not forbidden(road, on_track, cars).any()
    assert forbidden(road, in_bike_lane, cars).all()
    assert not forbidden(road, in_bike_lane, np.full(len(xs), "bicycle", dtype=object)).any()
    assert not road.lanes.against(on_track, np.tile([1.0, 0.0], (len(xs), 1))).any()
