import numpy as np
import pytest

from sumo_avoid.road.polyline import polyline_project_many, polyline_track

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


def _track_point_by_point(path, points, s_start=None, window_m=30.0):
    """polyline_track as it was before it was vectorised: one projection per point on its window."""
    p = np.asarray(path, float)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))])
    out, prev = np.zeros(len(points)), s_start
    for i, point in enumerate(np.asarray(points, float)):
        if prev is None:
            prev = float(polyline_project_many(p, point[None])[0])
        else:
            lo = max(0, int(np.searchsorted(cum, prev - window_m, side="right")) - 1)
            hi = min(len(p), int(np.searchsorted(cum, prev + window_m, side="left")) + 1)
            prev = float(cum[lo] + polyline_project_many(p[lo:hi], point[None])[0])
        out[i] = prev
    return out


def test_tracking_gives_the_floats_of_a_projection_per_point():
    # random walks along random paths (some with a repeated vertex), windows narrower and wider than
    # a segment, with and without a start: the same arc lengths within 1e-12 relative (1e-9 m near
    # s = 0) -- two implementations, so not bit for bit; a wrong segment or branch is off by metres
    rng = np.random.default_rng(7)
    for trial in range(12):
        n_vertices = int(rng.integers(2, 120))
        path = np.cumsum(rng.normal(0.0, rng.uniform(0.5, 20.0), (n_vertices, 2)), axis=0)
        if trial % 4 == 0:
            path[1] = path[0]
        along = np.clip(np.cumsum(rng.integers(-1, 3, 30)), 0, n_vertices - 1)
        pts = path[along] + rng.normal(0.0, 3.0, (30, 2))
        start = None if trial % 3 else float(rng.uniform(0.0, 20.0))
        for window in (30.0, 2.0, 500.0, 0.0):  # 0: windows of one vertex, or none (both raise then)
            for q in (pts, pts[:1]):
                try:
                    ref = _track_point_by_point(path, q, start, window)
                except ValueError:
                    with pytest.raises(ValueError, match="empty polyline"):
                        polyline_track(path, q, start, window)
                    continue
                np.testing.assert_allclose(polyline_track(path, q, start, window), ref, rtol=1e-12, atol=1e-9)
    assert polyline_track([[1.0, 2.0]], [[5.0, 5.0], [6.0, 6.0]]).tolist() == [0.0, 0.0]  # a one-vertex path
    assert polyline_track(U_TURN, np.zeros((0, 2))).shape == (0,)


def test_an_out_and_back_spur_is_skipped_from_level_with_its_far_end_to_twice_as_far_ahead_as_across():
    """Colonias' 376317858#4, by hand: the line runs west to (10, 0), an edge's lane laid 12 m back sends
    it east to (22, 0.5), and it comes west again from there, past x = 10 on (21, 1) -> (5, 1). The way
    back starts at x = 22, behind the way in's vertex (20, 0): the line leaves the way in there and
    rejoins the way back (1 m across) 2 m ahead, at (18, 1)."""
    from sumo_avoid.road.polyline import cut_spurs

    pts = np.array([[30.0, 0.0], [20.0, 0.0], [10.0, 0.0], [22.0, 0.5], [21.0, 1.0], [5.0, 1.0], [0.0, 1.0]])
    out, keep = cut_spurs(pts)
    assert keep.tolist() == [True, True, False, False, True, True, True]
    assert np.allclose(out[keep], [[30.0, 0.0], [20.0, 0.0], [18.0, 1.0], [5.0, 1.0], [0.0, 1.0]])


def test_a_hairpin_inside_a_junction_is_left_where_its_way_back_starts():
    """The shape netconvert gives a junction whose next edge's lane is laid 12 m back (the test net of
    tests/road/test_hook.py): in along y = -4.8 to x = -3.5, back to -15.27, out again east, 0.5 m across
    from (-15.07, -4.8) to (-9.75, -4.3). The line leaves the way in at x = -15.27 and keeps the way back."""
    from sumo_avoid.road.polyline import cut_spurs

    pts = np.array([[-200.0, -4.8], [-3.5, -4.8], [-15.27, -4.8], [-15.07, -4.8], [-9.75, -4.3], [1.15, -1.6]])
    out, keep = cut_spurs(pts)
    assert keep.tolist() == [True, True, True, True, True, True]
    assert np.allclose(out[1], [-15.27, -4.8]) and np.allclose(out[2], [-15.27 + 0.05, -4.8])
    assert np.allclose(out[3:], pts[3:])


def test_a_hook_that_turns_back_by_less_than_135_degrees_is_a_spur_too():
    """Unseen Chiang Mai, 688930917_1 -> 694361371_1 (a 0.2 m edge) -> :1814993162_5_0, by hand: the line runs
    west to (0, 0), the next lane starts 1.1 m back, at (0.5, -1) (a turn of 117 degrees: cosine -0.447), and the
    line goes on north-west from (0, -0.5). The way back starts at (0.5, -1): the line leaves the way in level with
    it, at (0.5, 0), and rejoins where it is twice as far ahead as across, on (0, -0.5) -> (-3, 2.5) at the first
    0.05 m sample past t = 1/6 of the way (0.25 m of line: (-0.25, 0.25) / sqrt(2) from (0, -0.5)). The hook
    bent the route frame's heading 1 rad over 10 m; the ego followed it out of its lane, stopped askew
    across two lanes and was hit 12 times."""
    from sumo_avoid.road.polyline import cut_spurs

    pts = np.array([[10.0, 0.0], [0.0, 0.0], [0.5, -1.0], [0.0, -0.5], [-3.0, 2.5]])
    out, keep = cut_spurs(pts)
    assert keep.tolist() == [True, True, False, True, True]
    r = 0.25 / np.sqrt(2.0)
    assert np.allclose(out[keep], [[10.0, 0.0], [0.5, 0.0], [-r, -0.5 + r], [-3.0, 2.5]])


@pytest.mark.parametrize("pts", [
    [[0.0, 0.0], [10.0, 0.0], [0.0, 3.0], [-20.0, 3.0]],  # a sharp U-turn: never back past x = 10 going east
    [[0.0, 0.0], [10.0, 0.0], [20.0, 1.0], [30.0, 5.0], [30.0, 20.0]],  # a left turn: no turn back at all
    [[0.0, 0.0], [10.0, 0.0], [-50.0, 1.0], [20.0, 2.0]],  # back past it, but beyond 50 m of line
])
def test_a_u_turn_a_turn_and_a_long_excursion_are_kept(pts):
    from sumo_avoid.road.polyline import cut_spurs

    out, keep = cut_spurs(np.array(pts))
    assert keep.all() and np.array_equal(out, np.array(pts))
