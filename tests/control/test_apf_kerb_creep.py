"""Two things a car does near people at the kerb and in a queue (control/apf/apf.py), pinned to
hand-computed values: a person standing behind the kerb beside the ego's strip pushes it like the kerb
(the edge's gain and reach), not like a car; creeping, the ego's command turns towards the road's direction."""
import numpy as np
import pytest

from sumo_avoid.control.apf.apf import ApfDriver, ApfParams, Field
from sumo_avoid.control.road_view import FrenetScene
from sumo_avoid.core.interfaces import Context


def _scene(kerb: bool, grow_m: float = 0.0, objects=True):
    """The ego (4.5 x 1.8 m, standing) at s 100, d 0, its lanes wide (no bound within reach); a person
    (0.5 x 0.48 m, standing) 1 m ahead of its centre with 0.5 m between its box and the ego's right side
    (d -1.64), on a walkway (``kerb``) or on the carriageway."""
    n = 1 if objects else 0
    return FrenetScene(100.0, 0.0, 0.0, np.zeros(2), 4.5, 1.8, np.array([[101.0, -1.64]])[:n], np.zeros(n),
                       np.full(n, 0.5 + grow_m), np.full(n, 0.48 + grow_m), np.zeros((n, 2)),
                       lambda s: (np.full(len(s), -10.0), np.full(len(s), 10.0)),
                       np.full(n, grow_m), 0.0, np.full(n, kerb))


def _push(kerb: bool, grow_m: float = 0.0) -> np.ndarray:
    drv, q, target = ApfDriver(ApfParams(), Context(seed=1, step_s=0.1)), np.array([[100.0, 0.0]]), np.array([115.0, 0.0])
    return drv.field(_scene(kerb, grow_m), q, target).F[0] - drv.field(_scene(kerb, objects=False), q, target).F[0]


def test_a_person_standing_behind_the_kerb_beside_the_strip_pushes_like_the_kerb():
    # beside (0.5 m > gov_margin 0.4 between the boxes across the road): pushes only across the road.
    # On a walkway: rho 0.5, reach min(rho0_beside 1.0, rho0_edge 0.8) = 0.8, gain k_edge 2:
    # 2 (1/0.5 - 1/0.8) / 0.5^2 = 6.0 m/s^2 away from it (left)
    assert _push(kerb=True) == pytest.approx([0.0, 6.0])
    # the same person on the carriageway (a car there alike): reach 1.0, gain k_rep 300: 300 (2 - 1) / 0.25 = 1200
    assert _push(kerb=False) == pytest.approx([0.0, 1200.0])


def test_a_person_on_a_walkway_who_keeps_its_margin_still_pushes_like_a_road_user():
    # walking towards the ego's path it keeps a share of the VRU margin (grown): no kerb discount; grown by
    # 0.2 m its box is 0.4 m from the ego's side: 300 (1/0.4 - 1) / 0.16 = 2812.5
    assert _push(kerb=True, grow_m=0.2) == pytest.approx([0.0, 2812.5])


@pytest.mark.parametrize("v_safe, course_deg", [(0.2, 0.0), (0.3, 0.0), (0.65, -17.5), (1.0, -35.0), (5.0, -35.0)])
def test_creeping_the_command_turns_towards_the_road(v_safe, course_deg):
    # a field pulling 45 degrees to the right; the governor allows v_safe. At or below 0.3 x creep_align_mps
    # (1.0) the command is along the road; at 0.65 the course may be half of max_course (35 deg): 17.5 deg;
    # from 1.0 on, the full 35 deg
    drv = ApfDriver(ApfParams(), Context(seed=1, step_s=0.1))
    v = drv.velocity(Field(np.zeros(1), np.array([[10.0, -10.0]]), v_safe), 13.89, speed_mps=0.0)
    if v_safe == 5.0:  # 35 deg at 5 m/s is 2.87 m/s across: held at max_lat_speed_mps 1.5
        assert v == pytest.approx([5.0 * np.cos(np.radians(35.0)), -1.5])
    else:
        assert np.hypot(*v) == pytest.approx(v_safe)
        assert np.degrees(np.arctan2(v[1], v[0])) == pytest.approx(course_deg, abs=1e-9)


def _cyclist_scene(clear_m: float) -> FrenetScene:
    """The ego (4.5 x 1.8 m, standing) at s 100, d 0; a cyclist (1.6 x 0.65 m, grown by the 1 m VRU margin on
    every side: 3.6 x 2.65 m) standing at 45 degrees to the road 3 m ahead, its body ``clear_m`` right of the
    ego's side. Its body's half span across the road: 0.5 (1.6 + 0.65) sin 45 = 0.7955 m."""
    d = -(0.9 + clear_m + 0.5 * (1.6 + 0.65) * np.sqrt(0.5))
    return FrenetScene(100.0, 0.0, 0.0, np.zeros(2), 4.5, 1.8, np.array([[103.0, d]]), np.array([np.pi / 4]),
                       np.array([3.6]), np.array([2.65]), np.zeros((1, 2)),
                       lambda s: (np.full(len(s), -10.0), np.full(len(s), 10.0)), np.array([2.0]), 0.0, np.array([False]))


def test_the_body_span_leaves_out_the_margin_of_a_turned_box():
    lo, hi = _cyclist_scene(0.8).body_span()
    assert (lo[0], hi[0]) == pytest.approx((-0.9 - 0.8 - 2 * 0.7955, -1.7), abs=1e-4)


@pytest.mark.parametrize("clear_m, v_safe", [(0.8, 2.0), (0.3, 0.0)])
def test_a_cyclist_standing_turned_beside_the_strip_is_passed_at_a_crawl(clear_m, v_safe):
    # the grown box, turned 45 degrees, reaches 0.5 (3.6 + 2.65) sin 45 = 2.21 m from its centre: 0.61 m into
    # the ego's strip at clear_m 0.8, and its rear 0.79 m ahead of the ego's centre, beside its front. Its body
    # is 0.8 m clear (> gov_margin 0.4): passed at squeeze_speed_mps 2.0 (before: counted as in the strip with
    # no gap, v_safe 0, for good). 0.3 m clear (< 0.4): in the strip, the ego stands
    drv = ApfDriver(ApfParams(), Context(seed=1, step_s=0.1))
    fld = drv.field(_cyclist_scene(clear_m), np.array([[100.0, 0.0]]), np.array([115.0, 0.0]))
    assert fld.v_safe == pytest.approx(v_safe)
