"""Lane lookup on real nets (sumo_avoid.road.lane_index via Road.lanes): which lane holds a point, its
direction there, junctions apart."""
import numpy as np
from conftest import ROOT

from sumo_avoid.road.network import Road


def test_lane_and_direction_on_the_left_turn_crossroads():
    road = Road.from_net_file(ROOT / "nets" / "left_turn.net.xml")
    lanes = road.lanes
    assert road.lanes is lanes  # built once per road
    assert all(not i.startswith(":") for i in lanes.ids)  # normal lanes only
    # S2C runs north at x = 1.75 (lane 1, inner) and 5.25 (lane 0); C2S south at -1.75 and -5.25;
    # W2C east at y = -1.75 and -5.25; (0, 0) is inside the junction, (30, -100) in the field
    pts = np.array([[1.75, -100.0], [5.25, -100.0], [-1.75, -100.0], [-100.0, -5.25], [0.0, 0.0], [30.0, -100.0]])
    lane, direction = lanes.lane_at(pts)
    assert [lanes.ids[k] if k >= 0 else None for k in lane] == ["S2C_1", "S2C_0", "C2S_1", "W2C_0", None, None]
    np.testing.assert_allclose(direction[:4], [[0, 1], [0, 1], [0, -1], [1, 0]], atol=1e-9)
    assert lanes.in_junction(pts).tolist() == [False, False, False, False, True, False]
    north = np.tile([0.0, 1.0], (len(pts), 1))
    assert lanes.against(pts, north).tolist() == [False, False, True, False, False, False]
    # on the border of two lanes the nearer centre line decides: 0.1 m into C2S_1 from the median
    lane, _ = lanes.lane_at([[-0.1, -100.0], [0.1, -100.0]])
    assert [lanes.ids[k] for k in lane] == ["C2S_1", "S2C_1"]


def test_lane_heading_places_points_in_normal_lanes_only():
    road = Road.from_net_file(ROOT / "nets" / "left_turn.net.xml")
    # S2C northbound, C2S southbound, W2C eastbound; inside the junction (internal lanes of every direction
    # overlap there) and in the field: none
    h = road.lane_heading(np.array([[1.75, -100.0], [-1.75, -100.0], [-100.0, -5.25], [0.0, 0.0], [30.0, -100.0]]))
    np.testing.assert_allclose(h[:3], [np.pi / 2, -np.pi / 2, 0.0], atol=1e-9)
    assert np.isnan(h[3:]).all()
    assert road.lane_heading(np.zeros((0, 2))).shape == (0,)
