"""APF-SA's escape bookkeeping (sumo_avoid.control.apf.apf_sa): when an escape ends, on hand-made
sequences of lateral positions (no SUMO)."""
from collections import deque

import numpy as np
import pytest

from sumo_avoid.control.apf.apf_sa import ApfSaController, ApfSaParams, _EgoState
from sumo_avoid.core.interfaces import Context


def _escaping(offset=7.0, t0=0.0):
    st = _EgoState(deque())
    st.escape_offset, st.escape_start_s, st.escape_clock_s = offset, t0, t0
    return st


def _run(ctl, st, ds, t0=0.0, dt=0.1, reversing=()):
    """Feed d(t) until the escape ends; the time it ended (or None)."""
    for k, d in enumerate(ds):
        t = t0 + dt * k
        st.reversing = k in reversing
        ctl._update_escape(st, d, t)
        if st.escape_offset is None:
            return round(t, 6)
    return None


@pytest.fixture
def ctl():
    return ApfSaController(ApfSaParams(), Context(seed=1, step_s=0.1))


def test_an_escape_without_progress_ends_after_the_timeout(ctl):
    # the ego stands at d = 0, 7 m from its offset: no step gets 0.5 m closer than the first
    assert _run(ctl, _escaping(), [0.0] * 200) == 10.0


def test_progress_restarts_the_timeout(ctl):
    # 0.6 m closer every 8 s for 40 s, then stuck at d = 3: the clock last restarts at 32 s
    ds = [0.6 * (k // 80) for k in range(400)] + [3.0] * 200
    ds[320:] = [2.4] * (len(ds) - 320)
    assert _run(ctl, _escaping(), ds) == 40.0  # escape_max_s reached first (32 + 10 > 40)


def test_backing_up_counts_as_part_of_the_manoeuvre(ctl):
    # backing up at steps 0..119 (last at 11.9 s) with no lateral progress, then standing: the
    # clock last restarts at 11.9 s, so the escape ends 10 s later
    assert _run(ctl, _escaping(), [0.0] * 400, reversing=range(120)) == 21.9


def test_an_escape_held_at_its_offset_ends_after_the_hold(ctl):
    # within 1 m of the offset from the start: held for escape_hold_s = 3 s
    assert _run(ctl, _escaping(), [6.5] * 100) == 3.0


def _scene_behind(gap_m, v_mps, d_o=0.0):
    """The ego (4.5 m) at s = 100, d = 0; one car (4.5 x 1.8) behind it, bumper to bumper ``gap_m``,
    at d_o, driving on at ``v_mps``."""
    import numpy as np

    from sumo_avoid.control.road_view import FrenetScene

    return FrenetScene(100.0, 0.0, 0.0, np.zeros(2), 4.5, 1.8, np.array([[100.0 - 4.5 - gap_m, d_o]]), np.zeros(1),
                       np.array([4.5]), np.array([1.8]), np.array([[v_mps, 0.0]]),
                       lambda s: (np.full(len(s), -5.0), np.full(len(s), 5.0)))


def test_backing_up_waits_for_the_traffic_behind(ctl):
    # a standing car 10 m behind: closing 1.5 m/s (the ego backing), clear beyond 3 + 3 x 1.5 = 7.5 m
    assert ctl._clear_behind(_scene_behind(10.0, 0.0))
    assert not ctl._clear_behind(_scene_behind(7.0, 0.0))
    # the same car driving on at 5 m/s: clear beyond 3 + 3 x 6.5 = 22.5 m
    assert not ctl._clear_behind(_scene_behind(10.0, 5.0))
    assert ctl._clear_behind(_scene_behind(23.0, 5.0))
    # in the next lane (d 3.5: its side at 2.6 > 0.9 + 0.4 from the ego's centre line) it does not count
    assert ctl._clear_behind(_scene_behind(2.0, 5.0, d_o=3.5))


def _scene_beside(d_o, v_mps, length=1.7, width=0.65, grow=0.0):
    """The ego (4.5 x 1.8) at s = 100, d = 0; one road user alongside its front half (centre at s = 101.5) at d_o."""
    import numpy as np

    from sumo_avoid.control.road_view import FrenetScene

    return FrenetScene(100.0, 0.0, 0.0, np.zeros(2), 4.5, 1.8, np.array([[101.5, d_o]]), np.zeros(1),
                       np.array([length]), np.array([width]), np.array([[v_mps, 0.0]]),
                       lambda s: (np.full(len(s), -5.0), np.full(len(s), 5.0)), o_grow=np.array([grow]))


def test_no_backing_up_while_someone_squeezes_past_alongside(ctl):
    # berlin_eastbound seed 3: a cyclist passing 0.0-0.3 m from the ego's side; backing up turned the car and
    # its nose swung into him. Within 0.9 + 0.5 m of the centre line, alongside: moving, or keeping a VRU margin
    assert not ctl._clear_behind(_scene_beside(-1.2, 1.0))  # its side 0.875 m from the centre line
    assert not ctl._clear_behind(_scene_beside(-1.2, 0.0, grow=0.5))  # standing, a cyclist's margin
    assert ctl._clear_behind(_scene_beside(-1.8, 1.0))  # its side at 1.475 > 1.4: clear
    assert ctl._clear_behind(_scene_beside(-2.25, 0.0, 4.5, 1.8))  # a parked car 0.45 m off: the escape goes on
    assert not ctl._clear_behind(_scene_beside(-2.25, 2.0, 4.5, 1.8))  # ... a moving one does not let it back up


def _scene_ahead(gap_m, ego_speed_mps):
    import numpy as np

    from sumo_avoid.control.road_view import FrenetScene

    return FrenetScene(100.0, 0.0, 0.0, np.array([ego_speed_mps, 0.0]), 4.5, 1.8,
                       np.array([[100.0 + 4.5 + gap_m, 0.0]]), np.zeros(1), np.array([4.5]), np.array([1.8]),
                       np.zeros((1, 2)), lambda s: (np.full(len(s), -5.0), np.full(len(s), 5.0)))


def test_an_escape_starts_only_with_room_for_the_move_across():
    # turning radius 4.25 m, standstill gap 2 m, a car standing 6.5 m (bumper to bumper) ahead in the lane.
    # A shift of 1 m takes two arcs with 1 - cos a = 2/17, sin a = 8/17: 8.5 x 8/17 = 4 m, + 2 = 6 <= 6.5;
    # a lane's 3.2 m takes 8.5 x sqrt(1 - (1 - 3.2/8.5)^2) = 6.645 m, + 2 = 8.645 > 6.5
    ctl = ApfSaController(ApfSaParams(), Context(seed=1, step_s=0.1, turn_radius_m=4.25))
    moving, standing = _scene_ahead(6.5, 5.0), _scene_ahead(6.5, 0.0)
    assert ctl._room_to_escape(moving, 1.0, sees_behind=False)
    assert not ctl._room_to_escape(moving, 3.2, sees_behind=False)  # a front radar alone: no swerve it cannot finish
    assert not ctl._room_to_escape(standing, -3.2, sees_behind=False)  # ... it waits aligned
    assert ctl._room_to_escape(moving, 3.2, sees_behind=True)  # seeing behind (nothing there), it can back up for room
    assert ctl._room_to_escape(standing, 3.2, sees_behind=True)
    assert ctl._room_to_escape(_scene_ahead(8.7, 5.0), 3.2, sees_behind=False)


def test_the_field_keys_sit_in_the_apf_sa_table_itself_and_reach_its_driver():
    """ApfSaParams holds ApfParams as an inline field: [controllers.apf_sa] takes APF's keys beside
    its own (no sub-table), they are documented under controllers.apf_sa, and the APF driver it
    delegates to drives with them."""
    from sumo_avoid.control.apf.apf import ApfParams
    from sumo_avoid.core.config import ScenarioError, build, describe

    p = build(ApfSaParams, {"k_rep": 5.0, "sa_t0": 3.0}, "s.toml", "controllers.apf_sa")
    assert p.apf == ApfParams(k_rep=5.0) and p.sa_t0 == 3.0
    assert ApfSaController(p, Context(seed=1, step_s=0.1)).driver.p is p.apf
    with pytest.raises(ScenarioError, match=r"'controllers.apf_sa.apf': expected one of the known keys \['creep_align_mps', 'curve_decel"):
        build(ApfSaParams, {"apf": {}}, "s.toml", "controllers.apf_sa")
    with pytest.raises(ScenarioError, match=r"'controllers.apf_sa.k_rep': expected a non-negative number"):
        build(ApfSaParams, {"k_rep": -1.0}, "s.toml", "controllers.apf_sa")
    rows = describe(ApfSaParams, "controllers.apf_sa")
    apf = [r[0].replace("controllers.apf.", "controllers.apf_sa.") for r in describe(ApfParams, "controllers.apf")]
    assert [r[0] for r in rows[:len(apf)]] == apf and rows[len(apf)][0] == "controllers.apf_sa.trap_window_s"


def test_the_legal_limit_where_the_ego_is_counts_as_cruising():
    """APF-SA's trap detector compares progress with min(cruise, curve speed, legal limit): by hand, limits
    13.89 m/s from 0, 8.33 from 100 m, an internal lane's turning speed 5.0 from 150 m (not a legal limit: the
    limit before the junction runs on through it), 13.89 from 160 m."""
    from sumo_avoid.control.road_view import RoadView
    from sumo_avoid.core.types import EgoTask

    path = np.array([[0.0, 0.0], [300.0, 0.0]])
    lim = np.array([[0.0, 13.89, 0.0], [100.0, 8.33, 0.0], [150.0, 5.0, 1.0], [160.0, 13.89, 0.0]])
    view = RoadView(EgoTask("ego", path[-1], path, 13.89, speed_limits=lim))
    assert [view.legal_speed(s) for s in (0.0, 50.0, 100.0, 120.0, 155.0, 170.0)] == [13.89, 13.89, 8.33, 8.33, 8.33, 13.89]
    assert RoadView(EgoTask("ego", path[-1], path, 13.89)).legal_speed(50.0) == np.inf
