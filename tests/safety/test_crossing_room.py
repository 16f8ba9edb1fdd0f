"""``room_beyond`` and ``stands_on_crossing`` (the rules layer's "never stop on a crossing"): on a straight
path along x with a crossing leaving it at x = 20 m and an ego of 4.8 m needing 5.8 m beyond it; a stop
line just beyond a crossing the ego is on. Hand-computed cases."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.road.crossings import stands_on_crossing
from sumo_avoid.safety.crossing_rule import LEAD_DECEL_MPS2, room_beyond

PATH = np.array([[0.0, 0.0], [50.0, 0.0], [100.0, 0.0]])
CROSSING = SimpleNamespace(s_exit_m=20.0)
NEED_M = 5.8


def _snap(x, vx, vy=0.0, person=False, length=4.5):
    """The ego standing at x = 5 and one other road user at (x, 0) moving at (vx, vy)."""
    return Snapshot(0.0, ("ego", "other"), [[5.0, 0.0], [x, 0.0]], [[0.0, 0.0], [vx, vy]], [0.0, 0.0],
                    [4.8, length], [1.8, 1.8], [True, False], is_person=np.array([False, person]))


@pytest.mark.parametrize("x, vx, vy, person, room", [
    (24.0, 0.0, 0.0, False, False),  # standing: rear 21.75 < 25.8
    (30.0, 0.0, 0.0, False, True),  # standing: rear 27.75 beyond 25.8
    (24.0, 3.0, 0.0, False, False),  # slowing queue: rear 21.75 + 9 / 9 = 22.75 < 25.8 (the old rule: room)
    (24.0, 7.0, 0.0, False, True),  # 21.75 + 49 / 9 = 27.19 > 25.8
    (24.0, 14.0, 0.0, False, True),  # driving on
    (24.0, 0.0, 3.0, False, True),  # crossing the path (a foe: the yield rules judge it), not going its way
    (24.0, -3.0, 0.0, False, True),  # coming the other way
    (22.0, 0.0, 0.0, True, False),  # a person standing on the path beyond the crossing
    (22.0, 3.0, 0.0, True, True),  # a person walking (no brake gap: only standing people count)
])
def test_room_beyond_a_crossing(x, vx, vy, person, room):
    assert LEAD_DECEL_MPS2 == 4.5
    assert room_beyond(CROSSING, PATH, _snap(x, vx, vy, person, 0.5 if person else 4.5), 0, NEED_M) is room


def _links(*spans):
    return (SimpleNamespace(crossings=tuple(SimpleNamespace(s_enter_m=a, s_exit_m=b) for a, b in spans)),)


@pytest.mark.parametrize("s_front, s_line, stands", [
    (23.0, 28.8, True),  # on the crossing (22-25.9), the line 2.9 m beyond it: a 4.8 m car stands on it
    (21.0, 28.8, False),  # not on it yet: it can wait before the crossing
    (23.0, 31.0, False),  # the line 5.1 m beyond: room for the car between them
    (23.0, 30.6, True),  # its rear at 25.8: 0.1 m on the crossing
    (23.0, 30.7, False),  # its rear at 25.9, the crossing's end: off it
])
def test_a_stop_at_a_line_just_beyond_a_crossing_it_is_on_stands_on_it(s_front, s_line, stands):
    assert stands_on_crossing(_links((22.0, 25.9)), s_front, s_line, 4.8) is stands


def test_the_room_asked_beyond_a_crossing_holds_a_car_stopping_at_apf_sas_standstill_gap():
    """berlin_eastbound seed 6 (truth): a car stood with its rear 6 m beyond a crossing at a junction's exit; the
    rule asked the 4.5 m ego for 4.5 + 1 m and let it in, and APF-SA, stopping 2 m behind the car (its governor's
    standstill gap), stood with its rear 0.5 m on the crossing. The room asked covers the length and that gap."""
    from sumo_avoid.control.apf.apf import ApfParams
    from sumo_avoid.safety.crossing_rule import ROOM_M
    gap = ApfParams().gov_standstill_m
    assert ROOM_M >= gap
    # the standing car's rear 6 m beyond the crossing's exit (x = 20): the ego would stop with its rear at 20 - 0.5
    assert not room_beyond(CROSSING, PATH, _snap(26.0 + 2.25, 0.0), 0, 4.5 + ROOM_M)
    # its rear 4.5 + ROOM_M + 0.1 m beyond: room
    assert room_beyond(CROSSING, PATH, _snap(20.0 + 4.5 + ROOM_M + 0.1 + 2.25, 0.0), 0, 4.5 + ROOM_M)
