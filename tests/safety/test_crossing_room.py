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


def _cap_where_the_ego_has_the_way(u, w):
    """CrossingRule.cap for an ego (4.8 m, front at s = 10 m, 10 m/s) before a crossing where cars have the way:
    the crossing runs across the path at x = 20-24 m from (22, 6) to (22, -6), the path passing over it at 6 m
    from its first end; one person on it u m from its first end, walking w m/s
    along it (towards the path: +)."""
    from sumo_avoid.road.crossings import CrossingLink
    from sumo_avoid.road.regulation import RulesParams
    from sumo_avoid.safety.crossing_rule import CrossingRule

    c = CrossingLink(":J_c0", ":J_c0_0", (":J_w0_0", ":J_w1_0"), ((22.0, 6.0), (22.0, -6.0)), 20.0, 24.0,
                     gives_way=False, strip=(6.0, 6.0))
    task = SimpleNamespace(links=(SimpleNamespace(crossings=(c,), tls="", s_stop_m=100.0),), path=PATH)
    snap = Snapshot(0.0, ("ego", "walker"), [[7.6, 0.0], [22.0, 6.0 - u]], [[10.0, 0.0], [0.0, -w]], [0.0, -np.pi / 2],
                    [4.8, 0.215], [1.8, 0.478], [True, False], is_person=np.array([False, True]),
                    lane=("E_0", ":J_c0_0"))
    return CrossingRule(RulesParams()).cap(task, 10.0, 10.0, snap, 0, 4.8)


@pytest.mark.parametrize("u, w, held", [
    (6.0, 1.2, True),  # in the path's stretch (6 +- 0.9 + 1 m margin: 4.1-7.9)
    (7.5, 1.2, True),  # past the path but within its stretch, walking away from it
    (8.5, 1.2, False),  # ... beyond the stretch, walking away
    # walking towards it: the ego (10 m/s, from 1.5 m/s^2) has its rear off the crossing in
    # (-10 + sqrt(100 + 3 x (24 + 4.8 - 10))) / 1.5 = 1.671 s, when the person has walked 2.005 m
    (2.1, 1.2, True),  # 2.0 m before the stretch
    (2.0, 1.2, False),  # 2.1 m before it: past the path before the person gets there
    (2.1, 0.0, False),  # standing on it, out of the way
])
def test_where_the_ego_has_the_way_a_person_on_the_crossing_in_its_way_holds_it_before_the_crossing(u, w, held):
    # the ego would otherwise stop on the crossing for the person (bologna_signals, radar, seeds 5, 7, 10)
    cap, line = _cap_where_the_ego_has_the_way(u, w)
    # held: it stops 1 m before the crossing, 10 m ahead, braking at 3 m/s^2: sqrt(2 x 3 x 9)
    assert (cap, line) == ((pytest.approx(np.sqrt(54.0)), 20.0) if held else (np.inf, -1.0))
