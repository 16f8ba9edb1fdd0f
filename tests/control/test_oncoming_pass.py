"""The oncoming-lane pass's arithmetic (control/apf/oncoming_pass.py), pinned by hand."""
from __future__ import annotations

import math

import pytest

from sumo_avoid.control.apf.oncoming_pass import OncomingPass, PassParams


def test_time_to_drive_a_pass_speeding_up_then_cruising():
    op = OncomingPass(PassParams(pass_accel_mps2=1.5))
    # from standstill 12 m at 1.5 m/s^2: sqrt(2 * 12 / 1.5) = 4 s
    assert op.time_to(12.0, 0.0, 10.0) == pytest.approx(4.0)
    # 50 m to cruise 10 m/s: 6.67 s and 33.3 m speeding up, 16.7 m at 10 m/s: 1.67 s
    assert op.time_to(50.0, 0.0, 10.0) == pytest.approx(10.0 / 1.5 + (50.0 - 100.0 / 3.0) / 10.0)
    assert op.time_to(0.0, 5.0, 10.0) == 0.0


def test_the_oncoming_lane_is_free_when_every_car_comes_late_enough():
    op = OncomingPass(PassParams(pass_margin_s=3.0))
    # the pass ends at s 100 in 6 s: a car at s 250 closing at 15 m/s arrives in 10 s > 9 s; at s 220, 8 s
    assert op.clear([(250.0, -15.0)], 100.0, 6.0)
    assert not op.clear([(220.0, -15.0)], 100.0, 6.0)
    assert not op.clear([(95.0, 0.0)], 100.0, 6.0)  # standing inside the stretch
    assert op.clear([], 100.0, 6.0) and math.isfinite(op.time_to(1.0, 0.0, 1.0))
