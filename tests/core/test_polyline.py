import numpy as np

from sumo_avoid.core.polyline import polyline_project_many, polyline_track

U_TURN = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 3.0], [0.0, 3.0]])  # out along y=0, back along y=3


def test_projection_of_many_points():
    s = polyline_project_many(U_TURN, [[50.0, 0.5], [100.5, 1.0], [20.0, 2.9]])
    assert np.allclose(s, [50.0, 101.0, 183.0])


def test_tracking_follows_the_branch_a_global_projection_would_skip():
    pts = [[40.0, 0.2], [50.0, 2.0], [60.0, 2.0], [99.0, 1.5], [80.0, 2.8]]
    assert polyline_project_many(U_TURN, pts[1:2])[0] == 153.0  # nearest point: the way back, y = 3
    s = polyline_track(U_TURN, pts)
    assert np.allclose(s, [40.0, 50.0, 60.0, 99.0, 123.0])  # 99: on the way out; 80 m back: 103 + 20
    assert np.allclose(polyline_track(U_TURN, [[50.0, 2.0]], s_start=150.0), [153.0])
