"""The compiled windowed projection against RouteFrame.to_frenet (numpy): the same (s, d), bit for bit."""
import numpy as np
import pytest

from sumo_avoid.road.frenet import RouteFrame


def _frames():
    rng = np.random.default_rng(3)
    yield RouteFrame.from_polyline([[0, 0], [100, 0]])
    yield RouteFrame.from_polyline([[0, 0], [50, 0], [80, 30], [80, 90], [20, 120]])
    for _ in range(6):  # random walks with bends of up to 60 deg
        head = np.cumsum(rng.uniform(-1.0, 1.0, 12))
        step = rng.uniform(3.0, 40.0, 12)
        pts = np.vstack([[0.0, 0.0], np.cumsum(np.column_stack([step * np.cos(head), step * np.sin(head)]), 0)])
        yield RouteFrame.from_polyline(pts)


@pytest.mark.parametrize("frame", list(_frames()))
def test_point_to_frenet_is_to_frenet(frame):
    rng = np.random.default_rng(7)
    s_true = rng.uniform(-20.0, frame.length_m + 20.0, 400)
    pts = frame.to_xy(np.clip(s_true, 0.0, frame.length_m), rng.uniform(-8.0, 8.0, 400)) + rng.normal(0, 0.5, (400, 2))
    hints = s_true + rng.uniform(-25.0, 25.0, 400)
    for k in range(len(pts)):
        s_np, d_np = frame.to_frenet(pts[k:k + 1], [hints[k]])
        s, d = frame.point_to_frenet(pts[k, 0], pts[k, 1], hints[k])
        # two implementations (compiled, numpy): equal within 1e-12 relative, not bit for bit (README:
        # the determinism contract holds per implementation and machine)
        assert (s, d) == pytest.approx((float(s_np[0]), float(d_np[0])), rel=1e-12, abs=1e-12) or (np.isnan(s) and np.isnan(s_np[0]))
        s_all, d_all = frame.to_frenet(pts[k:k + 1])
        assert frame.point_to_frenet(pts[k, 0], pts[k, 1], None) == pytest.approx((float(s_all[0]), float(d_all[0])), rel=1e-12, abs=1e-12)


def test_point_to_frenet_by_hand():
    frame = RouteFrame.from_polyline([[0, 0], [100, 0]])
    assert frame.point_to_frenet(30.0, 2.5, 25.0) == pytest.approx((30.0, 2.5), abs=1e-12)  # on a straight: s = x, d = y
    assert frame.point_to_frenet(-4.0, -1.0, 0.0) == pytest.approx((-4.0, -1.0), abs=1e-12)  # before the start: the extension
    assert frame.point_to_frenet(103.0, 1.0, 95.0) == pytest.approx((103.0, 1.0), abs=1e-12)  # past the end
    assert frame.point_to_frenet(30.0, 2.5, 90.0) == pytest.approx((30.0, 2.5), abs=1e-12)  # nothing in the window: the whole path
