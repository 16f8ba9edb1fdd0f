"""Which road users a controller keeps a person's margin to (sensing/perception.obstacle_vehicles)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.sensing.perception import obstacle_vehicles


def test_people_on_sidewalks_and_walking_areas_are_off_the_carriageway():
    # the ego; a person on a crossing, one on a sidewalk, one waiting on a corner's walking area, a
    # cyclist on a bike lane, a car
    ids = ("ego", "on_crossing", "on_sidewalk", "at_corner", "cyclist", "car")
    n = len(ids)
    pos = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, -4.0], [12.0, -6.0], [15.0, -2.5], [20.0, 0.0]])
    s = Snapshot(0.0, ids, pos, np.zeros((n, 2)), np.zeros(n), np.full(n, 4.5), np.full(n, 1.8),
                 [True] + [False] * (n - 1), vclass=("passenger", "pedestrian", "pedestrian", "pedestrian",
                                                     "bicycle", "passenger"),
                 is_person=np.array([False, True, True, True, False, False]),
                 lane=("E_1", ":J_c0_0", "E_0", ":J_w1_0", "E_bike", "E_1"))
    obs = SimpleNamespace(snapshot=s, detections=None)
    *_, vru, _ = obstacle_vehicles(obs, 0, pos[0], 50.0, walkways=frozenset({"E_0", ":J_w1_0"}))
    assert vru.tolist() == [1.0, 0.0, 0.0, 1.0, 0.0]  # all stand: the ones on walkways get no margin
    walking = Snapshot(0.0, ids, pos, np.tile([0.0, 1.2], (n, 1)), np.zeros(n), np.full(n, 4.5), np.full(n, 1.8),
                       [True] + [False] * (n - 1), vclass=s.vclass, is_person=s.is_person, lane=s.lane)
    *_, vru, _ = obstacle_vehicles(SimpleNamespace(snapshot=walking, detections=None), 0, pos[0], 50.0,
                                walkways=frozenset({"E_0", ":J_w1_0"}))
    assert vru.tolist() == [1.0, 0.5, 0.5, 1.0, 0.0]  # walking there: half the margin
    *_, vru, _ = obstacle_vehicles(obs, 0, pos[0], 50.0)  # no walkways known: every person and cyclist
    assert vru.tolist() == [1.0, 1.0, 1.0, 1.0, 0.0]


def test_a_person_walking_along_the_kerb_is_passed_at_its_size():
    from sumo_avoid.sensing.perception import towards_path

    # shares (perception._weight): on the carriageway 1, walking on a walkway 0.5, standing there 0, a car 0;
    # their speeds towards the ego's path across the road, m/s
    share = np.array([1.0, 0.5, 0.5, 0.5, 0.0, 0.0])
    closing = np.array([0.0, 0.0, 0.2, 0.3, -1.0, 2.0])
    # along the kerb (0, and at most 0.2 m/s towards it): no margin; walking up to the road (0.3): its half; on the
    # carriageway a person keeps the whole margin whichever way it walks; no margin for a car
    assert towards_path(share, closing).tolist() == [1.0, 0.0, 0.0, 0.5, 0.0, 0.0]


def test_a_person_at_the_kerb_far_off_the_traffic_direction_is_taken_to_stand():
    from sumo_avoid.core.types import Detections
    from sumo_avoid.sensing.perception import obstacle_vehicles, observable, velocity_estimate

    # the ego at 10 m/s along +x (the traffic's direction); a standing person at 70 degrees off, its radial speed
    # -10 cos 70 + 0.1 m/s of noise, and one at 40 degrees off walking along the road at -1.2 m/s
    a = np.radians([70.0, 40.0])
    vr = -10.0 * np.cos(a) + np.array([0.1, -1.2 * np.cos(a[1])])
    det = Detections(0.0, ("ego",), np.zeros((1, 2)), np.zeros(1), np.array([[10.0, 0.0]]), np.zeros(2, int),
                     np.full(2, 4.0), a, vr, vru=np.array([True, True]), walkway=np.array([True, True]))
    # the guess along the traffic divides by cos 70 = 0.342: the noise becomes 0.29 m/s along the road
    assert np.hypot(*velocity_estimate(det, np.arange(1), 0.0)[0]) == pytest.approx(0.1 / np.cos(a[0]))
    assert observable(det, np.arange(2), 0.0).tolist() == [False, True]  # cos 70 < 0.5 <= cos 40
    obs = SimpleNamespace(snapshot=SimpleNamespace(ids=("ego",)), detections=(det,), route_heading=np.array([0.0]),
                          index=lambda v: 0)
    *_, vel, share, _ = obstacle_vehicles(obs, 0, np.zeros(2), 50.0)
    assert vel[0].tolist() == [0.0, 0.0] and share[0] == 0.0  # taken to stand at the kerb: its size
    assert vel[1] == pytest.approx([-1.2, 0.0]) and share[1] == 0.5  # walking, read along the road


def test_a_car_return_in_a_lane_of_the_map_is_a_box_along_that_lane():
    from sumo_avoid.core.types import Detections

    # the ego's radar at the origin looking along +x at 10 m/s (the traffic's direction at the ego: 0 rad); three
    # returns 10 m off at 45 degrees, closing at 5 m/s: a car in a lane running north (the map: pi/2), one where the
    # map has no lane (inside a junction: NaN), a labelled cyclist in that northbound lane
    a = np.radians([45.0, 45.0, 45.0])
    det = Detections(0.0, ("ego",), np.zeros((1, 2)), np.zeros(1), np.array([[10.0, 0.0]]), np.zeros(3, int),
                     np.full(3, 10.0), a, np.full(3, -5.0), vru=np.array([False, False, True]),
                     walkway=np.zeros(3, bool), lane_heading=np.array([np.pi / 2, np.nan, np.pi / 2]))
    obs = SimpleNamespace(snapshot=SimpleNamespace(ids=("ego",)), detections=(det,), route_heading=np.array([0.0]),
                          index=lambda v: 0)
    pos, heading, length, width, vel, *_ = obstacle_vehicles(obs, 0, np.zeros(2), 50.0)
    r = 10.0 / np.sqrt(2.0)  # the return at (r, r)
    # along the lane (north): the return on the box's rear face, to its left (b = -r across the axis): the centre
    # half a length north and half a width east of it; moving north at the speed that explains -5 m/s:
    # (-5 + 10 cos 45) / cos 45 = 2.929 m/s
    assert heading[0] == pytest.approx(np.pi / 2)
    assert pos[0] == pytest.approx([r + 0.9, r + 2.25])
    assert vel[0] == pytest.approx([0.0, (-5.0 + 10.0 * np.cos(a[0])) / np.cos(a[0])], abs=1e-12)
    # no lane there: along the traffic's direction at the ego, the return on the box's left rear corner
    assert heading[1] == 0.0 and pos[1] == pytest.approx([r + 2.25, r + 0.9])
    # a cyclist's small box keeps the traffic's direction at the ego (a person's way is no lane's)
    assert heading[2] == 0.0 and length[2] == pytest.approx(1.8) and width[2] == pytest.approx(0.8)


def test_a_person_on_a_walkway_deep_in_the_ego_lanes_stands_on_the_carriageway():
    """perception.on_carriageway: lanes -1.6..1.6 across the road."""
    from sumo_avoid.sensing.perception import on_carriageway
    # centres: on a walking area over the lane (0.3), at a corner with its body 0.2 m into the lane (1.64), a radar
    # return of it 0.3 m further in (1.34), 0.6 m in (1.0), a person on the carriageway, a car (share 0, no walkway)
    share = [0.5, 0.0, 0.0, 0.0, 1.0, 0.0]
    kerb = [True, True, True, True, False, False]
    d = [0.3, 1.64, 1.34, 1.0, 0.0, 0.0]
    got_share, got_kerb = on_carriageway(share, kerb, d, -1.6, 1.6)
    assert got_share.tolist() == [1.0, 0.0, 0.0, 1.0, 1.0, 0.0]
    assert got_kerb.tolist() == [False, True, True, False, False, False]
    # the same on the lanes' other side
    got_share, _ = on_carriageway([0.0, 0.0], [True, True], [-1.34, -1.0], -1.6, 1.6)
    assert got_share.tolist() == [0.0, 1.0]
