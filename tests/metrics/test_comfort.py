"""Jerk and lateral acceleration (sumo_avoid.metrics.comfort) on hand-built recordings with
hand-computed values (m, s, rad)."""
import math

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.metrics.comfort import comfort


def ego_rows(vid, t, x, y, heading, speed, ego=True):
    return [{"step": k, "time_s": float(t[k]), "id": vid, "is_ego": ego, "x": float(x[k]), "y": float(y[k]),
                 "vx": float(speed[k] * math.cos(heading[k])), "vy": float(speed[k] * math.sin(heading[k])),
                 "speed": float(speed[k]), "heading": float(heading[k]), "length": 4.0, "width": 2.0} for k in range(len(t))]


def straight(vid, dt, s, ego=True):
    """Along the heading 30 degrees, arc length s at times k * dt."""
    t = dt * np.arange(len(s))
    h = np.full(len(s), math.radians(30.0))
    v = np.abs(np.gradient(s, t))
    return ego_rows(vid, t, s * np.cos(h), s * np.sin(h), h, v, ego)


def test_constant_acceleration_has_no_jerk_and_a_step_of_acceleration_is_da_over_dt():
    dt = 0.1
    t = dt * np.arange(30)
    smooth = straight("a", dt, 5.0 * t + 0.5 * 2.0 * t ** 2)  # a = 2 m/s^2 throughout
    m = comfort(pd.DataFrame(smooth))
    assert m["max_abs_jerk_mps3"] == pytest.approx(0.0, abs=1e-6)
    assert m["max_lat_accel_mps2"] == pytest.approx(0.0, abs=1e-9)
    # +3 m/s^2 then -8 m/s^2 from t = 1.5 s on (as the kinematic actuator brakes): the speed per
    # interval changes by +0.3 then -0.8 m/s, the acceleration by 11 m/s^2 within one step: 110 m/s^3
    v = np.r_[10.0 + 3.0 * dt * np.arange(15), 10.0 + 3.0 * dt * 14 - 8.0 * dt * np.arange(1, 15)]
    s = np.r_[0.0, np.cumsum(v * dt)]
    m = comfort(pd.DataFrame(straight("b", dt, s)))
    assert m["max_abs_jerk_mps3"] == pytest.approx(110.0, rel=1e-6)
    # the same profile recorded at 0.2 s: 11 m/s^2 within 0.2 s, 55 m/s^3 (step-level values)
    v2 = np.r_[10.0 + 3.0 * 0.2 * np.arange(8), 14.2 - 8.0 * 0.2 * np.arange(1, 8)]
    s2 = np.r_[0.0, np.cumsum(v2 * 0.2)]
    assert comfort(pd.DataFrame(straight("c", 0.2, s2)))["max_abs_jerk_mps3"] == pytest.approx(55.0, rel=1e-6)


def test_a_reversal_at_constant_deceleration_is_no_jerk():
    # s = 4t - t^2: forward, stops at t = 2, then backwards, a = -2 throughout; the recorded
    # speed |4 - 2t| has a kink there (SUMO reports reversing speeds as positive), the positions do not
    dt = 0.1
    t = dt * np.arange(41)
    m = comfort(pd.DataFrame(straight("r", dt, 4.0 * t - t ** 2)))
    assert m["max_abs_jerk_mps3"] == pytest.approx(0.0, abs=1e-6)


def test_lateral_acceleration_on_a_circle_across_the_heading_wrap():
    # 10 m/s on a circle of radius 50 m, counter-clockwise: v^2 / R = 2 m/s^2; the heading runs
    # from 150 to 210 degrees, crossing +pi -> -pi, which must not look like a 2 pi turn
    dt, v, r = 0.1, 10.0, 50.0
    t = dt * np.arange(60)
    phi = math.radians(60.0) + v / r * t  # polar angle; heading = phi + 90 degrees
    h = np.angle(np.exp(1j * (phi + math.pi / 2)))
    assert h.max() > 3.0 and h.min() < -3.0
    m = comfort(pd.DataFrame(ego_rows("c", t, r * np.cos(phi), r * np.sin(phi), h, np.full(len(t), v))))
    assert m["max_lat_accel_mps2"] == pytest.approx(2.0, rel=1e-3)  # central difference: 2 sin(0.02)/0.04
    assert m["max_abs_jerk_mps3"] == pytest.approx(0.0, abs=1e-6)


def test_max_over_egos_only_and_too_short():
    dt = 0.1
    t = dt * np.arange(10)
    rows = (straight("calm", dt, 5.0 * t) + straight("other", dt, np.r_[0, 0, 0, 0, 1, 2, 3, 4, 5, 6], ego=False))
    m = comfort(pd.DataFrame(rows))
    assert m["max_abs_jerk_mps3"] == pytest.approx(0.0, abs=1e-6)  # the non-ego's start does not count
    assert comfort(pd.DataFrame(straight("x", dt, np.array([0.0, 1.0])))) == {
        "max_abs_jerk_mps3": None, "max_lat_accel_mps2": None}
    three = comfort(pd.DataFrame(straight("x", dt, np.array([0.0, 1.0, 2.0]))))
    assert three["max_abs_jerk_mps3"] is None and three["max_lat_accel_mps2"] == pytest.approx(0.0)
