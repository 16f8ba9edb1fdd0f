"""Radar emulator: geometry against hand-computed values, occlusion, limits and noise statistics."""
import math

import numpy as np
import pytest
from radar_reference import _shadowed, visible_reference

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.sensing.occlusion import depth
from sumo_avoid.sensing.radar import Radar, RadarParams

EXACT = dict(range_sigma_m=0.0, speed_sigma_mps=0.0, angular_resolution_deg=0.0)


def snap(rows, t=0.0):
    """rows: (id, x, y, vx, vy, length, width); the first one is the ego, heading +x for all."""
    ids = tuple(r[0] for r in rows)
    a = np.array([r[1:] for r in rows], float)
    return Snapshot(t, ids, a[:, 0:2], a[:, 2:4], np.zeros(len(rows)), a[:, 4], a[:, 5],
                    [True] + [False] * (len(rows) - 1))


def radar(**kw):
    return Radar(RadarParams(**{**EXACT, **kw}), np.random.default_rng(7))


# ego: centre (0,0), length 4 -> sensor at (2, 0)
EGO = ("ego", 0.0, 0.0, 10.0, 0.0, 4.0, 1.8)


def by_target(det):
    return {t: i for i, t in enumerate(det.target)}


def test_ray_depth_unit_square():
    sq = np.array([[1.0, -1.0], [3.0, -1.0], [3.0, 1.0], [1.0, 1.0]])  # x in [1,3], y in [-1,1]
    d = [depth(sq, 4, a) for a in (0.0, math.atan2(1, 1), math.pi / 2, math.atan2(0.5, 1))]
    # straight ahead hits x=1 at 1; 45 deg hits the corner (1,1) at sqrt 2; 90 deg misses; (1,0.5)
    np.testing.assert_allclose(d, [1.0, math.sqrt(2), np.inf, math.hypot(1, 0.5)], atol=1e-12)


def test_shadow_prefilter_hand_built():
    """(The numpy reference's pre-filter; the kernel's is checked against it below.) Boxes as seen from the origin looking along +x (azimuths by hand):
    A: x 10..14, y -2..2 -> [-11.3, 11.3] deg, farthest corner 14.14 m;
    B: x 20..24, y -1..1 (inside A's cone, nearest point 20 m > 14.14) -> shadowed by A;
    C: x 20..24, y 3..5 (cone 7.1..14.0 deg, not inside A's) -> not shadowed;
    D: x 14.05..18, y -0.5..0.5 (inside the cone but nearest 14.05 m < 14.14 m) -> kept (conservative)."""
    box = lambda x0, x1, y0, y1: [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]  # noqa: E731
    rel = np.array([[box(10, 14, -2, 2), box(20, 24, -1, 1), box(20, 24, 3, 5), box(14.05, 18, -0.5, 0.5)]], float)
    az = np.arctan2(rel[..., 1], rel[..., 0])
    lo, hi = az.min(axis=2), az.max(axis=2)
    assert math.degrees(hi[0, 0]) == pytest.approx(11.3099, abs=1e-3)
    ok = np.ones((1, 4), bool)
    assert _shadowed(rel, lo, hi, ok).tolist() == [[False, True, False, False]]
    ok[0, 0] = False  # an occluder that is not a candidate shadows nothing
    assert not _shadowed(rel, lo, hi, ok).any()


def test_range_azimuth_radial_speed_hand_computed():
    # A: rear face at x = 20 -> range 18 straight ahead, relative speed 5 - 10 = -5 (closing)
    # D: nearest corner (32, 5.1) seen from (2, 0): range hypot(30, 5.1), azimuth atan2(5.1, 30),
    #    moving (0, -3): radial = ((0,-3) - (10,0)) . u
    s = snap([EGO, ("A", 22.25, 0.0, 5.0, 0.0, 4.5, 1.8), ("D", 34.25, 6.0, 0.0, -3.0, 4.5, 1.8)])
    det = radar().scan(s, ["ego"])
    k = by_target(det)
    assert det.range_m[k["A"]] == pytest.approx(18.0)
    assert det.azimuth_rad[k["A"]] == pytest.approx(0.0, abs=1e-12)
    assert det.radial_speed_mps[k["A"]] == pytest.approx(-5.0)
    assert det.range_m[k["D"]] == pytest.approx(math.hypot(30.0, 5.1))
    az = math.atan2(5.1, 30.0)  # the return is at the nearest point
    assert det.azimuth_rad[k["D"]] == pytest.approx(az, abs=1e-6)
    assert det.radial_speed_mps[k["D"]] == pytest.approx(-10 * math.cos(az) - 3 * math.sin(az))
    np.testing.assert_allclose(det.points()[k["A"]], [20.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(det.points()[k["D"]], [32.0, 5.1], atol=1e-4)


def test_target_behind_another_is_hidden_then_seen_when_uncovered():
    lead = ("A", 22.25, 0.0, 0.0, 0.0, 4.5, 1.8)
    hidden = ("B", 42.25, 0.0, 0.0, 0.0, 4.5, 1.8)
    r = radar()
    assert by_target(r.scan(snap([EGO, lead, hidden]), ["ego"])).keys() == {"A"}
    moved = ("A", 22.25, 3.5, 0.0, 0.0, 4.5, 1.8)  # the lead changes lane
    det = r.scan(snap([EGO, moved, hidden], t=0.1), ["ego"])
    assert by_target(det).keys() == {"A", "B"}
    assert det.range_m[by_target(det)["B"]] == pytest.approx(38.0)


def test_partly_hidden_target_is_measured_on_its_visible_part():
    # A hides azimuths up to atan(0.9/18); C spans y in [0.6, 2.4] at x >= 40 (rel. x >= 38):
    # its nearest visible point is on its rear face where the shadow ends, y = 38 * 0.9/18 = 1.9
    s = snap([EGO, ("A", 22.25, 0.0, 0.0, 0.0, 4.5, 1.8), ("C", 42.25, 1.5, 0.0, 0.0, 4.5, 1.8)])
    det = radar().scan(s, ["ego"])
    k = by_target(det)
    assert set(k) == {"A", "C"}
    assert det.range_m[k["C"]] == pytest.approx(math.hypot(38.0, 1.9), abs=1e-4)
    assert det.azimuth_rad[k["C"]] == pytest.approx(math.atan2(0.9, 18.0), abs=1e-6)


def test_nothing_beyond_max_range_or_outside_fov():
    near = ("N", 2.0 + 90.0 + 2.25, 0.0, 0, 0, 4.5, 1.8)  # rear face at range 90
    far = ("F", 2.0 + 101.0 + 2.25, 20.0, 0, 0, 4.5, 1.8)  # nearest point ~103 m away
    inside = ("I", 2.0 + 20.0, 15.0, 0, 0, 1.0, 1.0)  # azimuth ~ 34 deg
    outside = ("O", 2.0 + 10.0, 15.0, 0, 0, 1.0, 1.0)  # azimuth ~ 56 deg > 45
    behind = ("B", -20.0, 0.0, 0, 0, 4.5, 1.8)
    s = snap([EGO, near, far, inside, outside, behind])
    det = radar(max_range_m=100.0, fov_deg=90.0).scan(s, ["ego"])
    assert set(det.target) == {"N", "I"}
    assert det.range_m.max() <= 100.0
    assert np.abs(det.azimuth_rad).max() <= math.radians(45.0)


def test_vectorised_over_egos_matches_one_at_a_time():
    rows = [EGO, ("e2", 50.0, -3.5, 8.0, 0.0, 4.5, 1.8), ("A", 22.25, 0.0, 5.0, 0.0, 4.5, 1.8),
            ("B", 70.0, -3.0, 2.0, 0.5, 12.0, 2.5), ("C", 30.0, -3.5, 0.0, 0.0, 4.5, 1.8)]
    s = Snapshot(0.0, tuple(r[0] for r in rows), [r[1:3] for r in rows], [r[3:5] for r in rows],
                 [0.0, 0.1, 0.0, 0.05, -0.02], [r[5] for r in rows], [r[6] for r in rows], [1, 1, 0, 0, 0])
    both = radar().measure(s, ["ego", "e2"])
    for k, vid in enumerate(["ego", "e2"]):
        one = radar().measure(s, [vid])
        sel = both.ego == k
        assert tuple(np.array(both.target, object)[sel]) == one.target
        np.testing.assert_allclose(both.range_m[sel], one.range_m)
        np.testing.assert_allclose(both.radial_speed_mps[sel], one.radial_speed_mps)


def test_static_obstacle_polygons_are_targets_and_occluders():
    wall = np.array([[30.0, -5.0], [31.0, -5.0], [31.0, 5.0], [30.0, 5.0]])
    s = snap([EGO, ("B", 52.25, 0.0, 0, 0, 4.5, 1.8)])
    det = radar().scan(s, ["ego"], obstacles=(wall,))
    assert det.target == ("obstacle0",)
    assert det.range_m[0] == pytest.approx(28.0)


def test_noise_statistics_match_sigma():
    s = snap([EGO, ("A", 52.25, 0.0, 4.0, 0.0, 4.5, 1.8)])  # true range 48, radial -6
    r = Radar(RadarParams(range_sigma_m=0.5, speed_sigma_mps=0.3, angular_resolution_deg=0.0),
              np.random.default_rng(3))
    n = 4000
    rng_err = np.empty(n)
    v_err = np.empty(n)
    for i in range(n):
        d = r.measure(s, ["ego"])
        rng_err[i], v_err[i] = d.range_m[0] - 48.0, d.radial_speed_mps[0] + 6.0
    for err, sigma in ((rng_err, 0.5), (v_err, 0.3)):
        assert abs(err.mean()) < 3 * sigma / math.sqrt(n)
        assert abs(err.std(ddof=1) / sigma - 1.0) < 0.10


def test_detection_probability_and_false_alarms():
    s = snap([EGO, ("A", 52.25, 0.0, 0, 0, 4.5, 1.8)])
    p, lam, n = 0.7, 0.5, 4000
    r = Radar(RadarParams(detection_prob=p, false_alarm_rate=lam, **EXACT), np.random.default_rng(5))
    hits = fas = 0
    for _ in range(n):
        d = r.measure(s, ["ego"])
        hits += d.target.count("A")
        fas += d.target.count("")
        assert (d.range_m <= 100.0).all() and (np.abs(d.azimuth_rad) <= math.radians(45)).all()
    assert abs(hits / n - p) < 3 * math.sqrt(p * (1 - p) / n)
    assert abs(fas / n - lam) < 3 * math.sqrt(lam / n)


def test_update_period_holds_last_scan_and_seed_determinism():
    s0 = snap([EGO, ("A", 22.25, 0.0, 0, 0, 4.5, 1.8)], t=0.0)
    s1 = snap([EGO, ("A", 32.25, 0.0, 0, 0, 4.5, 1.8)], t=0.1)
    r = Radar(RadarParams(update_period_s=0.2, **EXACT), np.random.default_rng(0))
    first = r.scan(s0, ["ego"])
    assert r.scan(s1, ["ego"]) is first  # 0.1 s later: held
    assert r.scan(snap([EGO, ("A", 32.25, 0.0, 0, 0, 4.5, 1.8)], t=0.2), ["ego"]).range_m[0] == pytest.approx(28.0)
    a = Radar(RadarParams(), np.random.default_rng(9)).measure(s0, ["ego"])
    b = Radar(RadarParams(), np.random.default_rng(9)).measure(s0, ["ego"])
    np.testing.assert_array_equal(a.range_m, b.range_m)


def test_params_validation():
    with pytest.raises(ValueError):
        RadarParams(fov_deg=200.0)
    with pytest.raises(ValueError):
        RadarParams(detection_prob=1.5)


def test_tracker_coasts_a_car_that_left_the_fov_and_drops_it_when_it_should_be_seen():
    from sumo_avoid.sensing.perception import perceived_obstacles, velocity_estimate

    r = Radar(RadarParams(memory_s=5.0, **EXACT), np.random.default_rng(0))
    # a car 10 m ahead-left in the next lane, 2 m/s slower: seen; radial-speed velocity estimate
    # along the heading recovers its 8 m/s exactly
    s0 = snap([EGO, ("A", 14.25, 3.5, 8.0, 0.0, 4.5, 1.8)], t=0.0)
    det = r.scan(s0, ["ego"])
    np.testing.assert_allclose(velocity_estimate(det), [[8.0, 0.0]], atol=1e-9)
    r.objects(det)
    # 4 s later the ego (10 m/s) is beside it: out of the FOV, no return; the memory coasts it
    s1 = snap([("ego", 45.0, 0.0, 10.0, 0.0, 4.0, 1.8), ("A", 46.25, 3.5, 8.0, 0.0, 4.5, 1.8)], t=4.0)
    det1 = r.scan(s1, ["ego"])
    assert det1.n == 0
    obj = r.objects(det1)
    assert obj.n == 1 and obj.target == ("",)
    # the return (its rear-right corner (12, 2.6) at t = 0) coasted 4 s at 8 m/s: (44, 2.6)
    np.testing.assert_allclose(obj.points(), [[44.0, 2.6]], atol=1e-6)
    assert obj.radial_speed_mps[0] == pytest.approx(-2.0 * math.cos(obj.azimuth_rad[0]))
    assert len(perceived_obstacles(obj, "ego")[0]) == 1
    # a remembered return predicted inside the FOV but not seen again is dropped
    s2 = snap([("ego", 0.0, 0.0, 10.0, 0.0, 4.0, 1.8)], t=0.1)
    r2 = Radar(RadarParams(memory_s=5.0, **EXACT), np.random.default_rng(0))
    r2.objects(r2.scan(snap([EGO, ("B", 30.0, 0.0, 10.0, 0.0, 4.5, 1.8)]), ["ego"]))
    assert r2.objects(r2.scan(s2, ["ego"])).n == 0


def test_detection_log_table():
    from sumo_avoid.sensing.log import detections_table

    r = Radar(RadarParams(log_detections=True, **EXACT), np.random.default_rng(0))
    r.scan(snap([EGO, ("A", 22.25, 0.0, 5.0, 0.0, 4.5, 1.8)]), ["ego"])
    r.scan(snap([EGO, ("A", 22.25, 0.0, 5.0, 0.0, 4.5, 1.8)], t=0.1), ["ego"])
    df = detections_table(r.log)
    assert len(df) == 2 and list(df["target"]) == ["A", "A"]
    np.testing.assert_allclose(df[["x", "y"]].to_numpy(), [[20.0, 0.0]] * 2, atol=1e-6)
    assert detections_table([]).empty


def test_tracker_gate_matches_only_returns_of_the_same_ego():
    from sumo_avoid.sensing.tracker import _near_same_ego

    p = np.array([[0.0, 0.0], [0.0, 0.0], [100.0, 0.0]])
    e = np.array([0, 1, 1])
    q = np.array([[2.0, 0.0], [0.5, 0.0], [102.9, 0.0]])  # 2 m from p0 (ego 0), 0.5 m (ego 2), 2.9 m (ego 1)
    f = np.array([0, 2, 1])
    assert _near_same_ego(p, e, q, f, 3.0).tolist() == [True, False, True]
    assert _near_same_ego(p, e, q, f, 1.0).tolist() == [False, False, False]


def test_rear_radar_sees_behind_not_ahead():
    """Rear radar at the rear bumper (x = -2 for the 4 m ego), boresight -x: car B 20 m behind
    (front bumper at x = -17.75 ... nearest point 15.75 m) closing at 3 m/s is seen; A ahead is not."""
    s = snap([EGO, ("A", 22.25, 0.0, 5.0, 0.0, 4.5, 1.8), ("B", -20.0, 0.0, 13.0, 0.0, 4.5, 1.8)])
    det = Radar(RadarParams(**EXACT), np.random.default_rng(0), mount="rear").scan(s, ["ego"])
    assert det.mount == "rear" and det.target == ("B",)
    np.testing.assert_allclose(det.sensor_pos, [[-2.0, 0.0]], atol=1e-12)
    assert det.range_m[0] == pytest.approx(15.75) and det.azimuth_rad[0] == pytest.approx(0.0)
    assert det.radial_speed_mps[0] == pytest.approx(-3.0)  # closing
    with pytest.raises(ValueError):
        Radar(RadarParams(), np.random.default_rng(0), mount="roof")


def test_side_radars_see_the_car_alongside_that_front_and_rear_radars_cannot():
    """Car C alongside on the left (centre (0, 3.2), right edge at y = 2.3, x -2.25 .. 2.25) at the
    ego's speed. The left radar sits mid-flank at (0, 0.9), boresight +y: C's nearest point (0, 2.3)
    at range 1.4, azimuth 0, radial speed 0. The right radar sees nothing; the front radar (x = 2,
    +x) sees nothing of C behind its bumper line; the rear one (x = -2, -x) sees only C's last 0.25 m,
    84 degrees off its boresight (> 45): nothing. Car F at (30, 3.2) is 87 degrees off the left
    radar's boresight (> 75, the side field of view's half): the front radar's, not the left's."""
    s = snap([EGO, ("C", 0.0, 3.2, 10.0, 0.0, 4.5, 1.8), ("F", 30.0, 3.2, 10.0, 0.0, 4.5, 1.8)])
    p = RadarParams(**EXACT, side=True)
    assert p.mounts() == ("front", "left", "right")
    left, right, front, rear = (Radar(p, np.random.default_rng(0), mount=m).scan(s, ["ego"])
                                for m in ("left", "right", "front", "rear"))
    assert left.mount == "left" and left.target == ("C",)
    np.testing.assert_allclose(left.sensor_pos, [[0.0, 0.9]], atol=1e-12)
    assert left.sensor_heading[0] == pytest.approx(math.pi / 2)
    assert left.range_m[0] == pytest.approx(1.4) and left.azimuth_rad[0] == pytest.approx(0.0, abs=1e-12)
    assert left.radial_speed_mps[0] == pytest.approx(0.0, abs=1e-12)
    assert right.n == 0 and rear.n == 0 and front.target == ("F",)
    # the side radars' own range: C 45 m to the left is beyond side_range_m = 40
    far = snap([EGO, ("C", 0.0, 45.0, 10.0, 0.0, 4.5, 1.8)])
    assert Radar(p, np.random.default_rng(0), mount="left").scan(far, ["ego"]).n == 0
    with pytest.raises(ValueError):
        RadarParams(side_fov_deg=180.0)


def test_tracker_judges_each_mount_by_its_own_field_of_view():
    """One memory over the front and left radars. A standing car C is seen ahead-left by the front
    radar (its rear-right corner (17.75, 2.3); the left radar's field of view, 75 degrees off its
    boresight, passes in front of it); 1 s later the ego (20 m/s) is beside it: from the left radar
    at (20, 0.9) the remembered point is 58 degrees off the boresight, inside the side
    field of view (75) though outside the front one's (45). C still there: re-observed, 1 return;
    C gone: dropped, 0 (judged by the front radar's 45 degrees it would have been kept)."""
    from sumo_avoid.sensing.tracker import Tracker

    p = RadarParams(**EXACT, side=True, memory_s=5.0)
    radars = [Radar(p, np.random.default_rng(0), mount=m) for m in ("front", "left")]
    s0 = snap([("ego", 0.0, 0.0, 20.0, 0.0, 4.0, 1.8), ("C", 20.0, 3.2, 0.0, 0.0, 4.5, 1.8)], t=0.0)
    ego1 = ("ego", 20.0, 0.0, 20.0, 0.0, 4.0, 1.8)
    for later, views, kept in ((snap([ego1, ("C", 20.0, 3.2, 0.0, 0.0, 4.5, 1.8)], t=1.0), {"left": (150.0, 40.0)}, 1),
                               (snap([ego1], t=1.0), {"left": (150.0, 40.0)}, 0),
                               (snap([ego1], t=1.0), None, 1)):
        tr = Tracker(5.0, 90.0, 100.0, views=views)
        first = tr.update(tuple(r.scan(s0, ["ego"], force=True) for r in radars), np.array([0.0]))
        assert first[0].target == ("C",) and first[1].n == 0
        out = tr.update(tuple(r.scan(later, ["ego"], force=True) for r in radars), np.array([0.0]))
        assert out[0].n + out[1].n == kept


def test_assumed_boxes_have_the_return_on_their_near_side():
    """Seen from the front radar at (2, 0): car A straight ahead (centre (20, 0)) returns the middle
    of its rear face (17.75, 0): box centre 2.25 m on, (20, 0). Car B ahead in the next lane (centre
    (9, 3.5)) returns its rear-right corner (6.75, 2.6): centre 2.25 m on and 0.9 m across, (9, 3.5)
    exactly (pushed back along the line of sight it was (8.86, 3.76): 0.26 m into the lane beyond).
    From the left radar at (0, 0.9), car C alongside (centre (0, 3.2)) returns the middle of its side
    (0, 2.3): centre 0.9 m across, (0, 3.2)."""
    from sumo_avoid.sensing.perception import perceived_boxes

    s = snap([EGO, ("A", 20.0, 0.0, 10.0, 0.0, 4.5, 1.8), ("B", 9.0, 3.5, 10.0, 0.0, 4.5, 1.8)])
    det = Radar(RadarParams(**EXACT), np.random.default_rng(0)).scan(s, ["ego"])
    pos = perceived_boxes(det, along=0.0)[0]
    got = {t: pos[i] for i, t in enumerate(det.target)}
    np.testing.assert_allclose(got["A"], [20.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(got["B"], [9.0, 3.5], atol=1e-9)
    side = snap([EGO, ("C", 0.0, 3.2, 10.0, 0.0, 4.5, 1.8)])
    det = Radar(RadarParams(**EXACT, side=True), np.random.default_rng(0), mount="left").scan(side, ["ego"])
    np.testing.assert_allclose(perceived_boxes(det, along=0.0)[0], [[0.0, 3.2]], atol=1e-9)


def test_velocity_estimate_along_the_road_not_the_turning_ego():
    """A car straight ahead-left moving at 13 m/s along +x, seen by an ego turned 0.5 rad left:
    along the ego's heading the estimate is wrong (has a y part); along the road (0 rad) exact."""
    from sumo_avoid.sensing.perception import perceived_obstacles, velocity_estimate

    ego = ("ego", 0.0, 0.0, 5.0 * math.cos(0.5), 5.0 * math.sin(0.5), 4.0, 1.8)
    s = snap([ego, ("A", 20.0, 8.0, 13.0, 0.0, 4.5, 1.8)])
    s = Snapshot(s.time_s, s.ids, s.pos, s.vel, np.array([0.5, 0.0]), s.length, s.width, s.is_ego)
    det = Radar(RadarParams(**EXACT), np.random.default_rng(0)).scan(s, ["ego"])
    assert det.n == 1
    assert abs(velocity_estimate(det)[0, 1]) > 1.0
    np.testing.assert_allclose(velocity_estimate(det, along=0.0), [[13.0, 0.0]], atol=1e-9)
    pos, hd, _, _, vel = perceived_obstacles(det, "ego", along=0.0)
    assert hd.tolist() == [0.0]
    np.testing.assert_allclose(vel, [[13.0, 0.0]], atol=1e-9)


def test_tracker_coasts_along_the_given_traffic_direction():
    """The ego is turned 0.3 rad left; car A ahead drives along +x at 8 m/s. Coasted along the
    ego's heading its track drifts sideways; along the route (0 rad) it stays in A's lane."""
    from sumo_avoid.sensing.tracker import Tracker

    ego = ("ego", 0.0, 0.0, 10.0 * math.cos(0.3), 10.0 * math.sin(0.3), 4.0, 1.8)
    s0 = snap([ego, ("A", 14.25, 3.5, 8.0, 0.0, 4.5, 1.8)], t=0.0)
    s0 = Snapshot(s0.time_s, s0.ids, s0.pos, s0.vel, np.array([0.3, 0.0]), s0.length, s0.width, s0.is_ego)
    det = Radar(RadarParams(memory_s=5.0, **EXACT), np.random.default_rng(0)).scan(s0, ["ego"])
    assert det.n == 1
    y0 = det.points()[0, 1]
    # 3 s later the ego is far to the left (nothing in view): only the coasted track is reported
    s1 = snap([("ego", 0.0, 60.0, 10.0, 0.0, 4.0, 1.8)], t=3.0)
    for along, sideways in ((np.array([0.0]), False), (None, True)):
        tr = Tracker(5.0, 90.0, 100.0)
        tr.update(det, along)
        out = tr.update(Radar(RadarParams(**EXACT), np.random.default_rng(0)).scan(s1, ["ego"]), along)
        assert out.n == 1
        drift = abs(out.points()[0, 1] - y0)
        assert (drift > 1.0) if sideways else drift == pytest.approx(0.0, abs=1e-9)


def test_route_directions_hand_values():
    from sumo_avoid.road.polyline import route_directions

    path = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0]])
    d = route_directions([path, None, path], np.array([[50.0, 2.0], [0.0, 0.0], [100.0, 50.0]]),
                         np.array([0.1, 0.2, 0.3]))
    np.testing.assert_allclose(d, [0.0, 0.2, math.pi / 2])


def _random_scene(rng, n_vehicles, n_egos, n_obstacles, dense=False):
    if dense:  # a jam: 3 lanes, 11.5 m apart (the radar benchmark's density), small heading noise
        k = np.arange(n_vehicles)
        pos = np.column_stack([(k // 3) * 11.5 + rng.normal(0, 0.3, n_vehicles), (k % 3) * 3.5])
        heading = rng.normal(0, 0.05, n_vehicles)
    else:
        pos = rng.uniform(-60, 60, (n_vehicles, 2))
        heading = rng.uniform(-np.pi, np.pi, n_vehicles)
    vel = rng.normal(0, 8, (n_vehicles, 2))
    length, width = rng.uniform(3.5, 12, n_vehicles), rng.uniform(1.6, 2.6, n_vehicles)
    ids = tuple(f"v{i}" for i in range(n_vehicles))
    s = Snapshot(0.0, ids, pos, vel, heading, length, width, np.arange(n_vehicles) < n_egos)
    obstacles = []
    for _ in range(n_obstacles):  # convex polygons with 3-8 vertices
        m = int(rng.integers(3, 9))
        ang = np.sort(rng.uniform(0, 2 * np.pi, m))
        obstacles.append(rng.uniform(-50, 50, 2) + rng.uniform(1, 6) * np.column_stack([np.cos(ang), np.sin(ang)]))
    return s, ids[:n_egos], obstacles


@pytest.mark.parametrize("mount", ["front", "rear", "left"])
def test_kernel_matches_the_numpy_reference(mount):
    """sensors/occlusion.py (numba) against the numpy formulation it replaced (tests/sensing/radar_reference.py):
    the same detections, the same values within 1e-12 relative (1e-12 absolute near zero) -- two
    implementations, so not bit for bit: numpy dispatches SIMD kernels by CPU (AVX-512 rounds the
    last bits of ``hypot``/``arctan2`` differently from the compiled loop) -- on 150 random scenes (vehicles of random
    sizes and headings, convex obstacles, a 150 deg and a 60 deg field of view) and 20 dense jams."""
    rng = np.random.default_rng(11)
    total = 0
    for k in range(170):
        dense = k >= 150
        s, egos, obstacles = _random_scene(rng, 60 if dense else int(rng.integers(2, 40)),
                                           6 if dense else int(rng.integers(1, 6)), 0 if dense else int(rng.integers(0, 3)),
                                           dense)
        r = Radar(RadarParams(**EXACT, fov_deg=150.0 if k % 2 else 60.0, max_range_m=80.0), np.random.default_rng(1),
                  mount=mount)
        got, ref = r.measure(s, egos, obstacles), visible_reference(r, s, egos, obstacles)
        assert got.target == ref["target"], k
        for f in ("ego", "range_m", "azimuth_rad", "radial_speed_mps"):
            np.testing.assert_allclose(getattr(got, f), ref[f], rtol=1e-12, atol=1e-12, err_msg=f"{k} {f}")
        total += got.n
    assert total > 1000  # the scenes do see things


def test_compiled_footprints_and_candidates_equal_the_numpy_and_kdtree_versions():
    """occlusion.boxes == geometry.footprint_corners within 1e-12 (two implementations: never bit for bit,
    a compiler may fuse a multiply-add the other rounds twice), and occlusion.candidates (a sweep
    along one axis) gives exactly the (ego, target) pairs of the k-d tree version it replaced, in
    the same order, on random scenes, dense jams and a road along y (the sweep then runs on y)."""
    from radar_reference import _candidates

    from sumo_avoid.core.geometry import footprint_corners
    from sumo_avoid.sensing.occlusion import boxes, candidates

    rng = np.random.default_rng(5)
    pairs = 0
    for k in range(120):
        s, egos, _ = _random_scene(rng, 60 if k % 3 == 0 else int(rng.integers(2, 50)), 6, 0, dense=k % 3 == 0)
        if k % 4 == 1:  # the same scene turned by 90 degrees: targets spread along y
            s = Snapshot(0.0, s.ids, s.pos[:, ::-1] * [-1, 1], s.vel, s.heading + np.pi / 2, s.length, s.width, s.is_ego)
        corners, centre, radius = boxes(s.pos, np.cos(s.heading), np.sin(s.heading), s.length, s.width)
        np.testing.assert_allclose(corners, footprint_corners(s.pos, s.heading, s.length, s.width), rtol=1e-12, atol=1e-12)
        r = Radar(RadarParams(fov_deg=[60.0, 150.0, 179.0][k % 3], max_range_m=[30.0, 80.0][k % 2]),
                  np.random.default_rng(1), mount=["front", "rear"][k % 2])
        rows = np.array([s.index[v] for v in egos])
        spos, _, fwd = r.pose(s, rows)
        half = math.radians(r.p.fov_deg) / 2
        e0, n0 = _candidates(spos, fwd, centre, radius, rows, r.p.max_range_m, half)
        e1, n1 = candidates(spos, fwd, centre, radius, rows, r.p.max_range_m, math.cos(half), math.sin(half))
        # integer (ego, target) pairs, a logical result: exact (a pair at the range bound to the last bit
        # could split the two, and these random scenes hold none)
        assert np.array_equal(e0, e1) and np.array_equal(n0, n1), k
        pairs += len(e1)
    assert pairs > 2000


def test_persons_and_cyclists_are_seen_at_a_shorter_range_than_cars():
    """Range 100 m: a car is seen at 60 m; a person only within 0.42 x 100 = 42 m, a cyclist within 56 m
    (their smaller radar cross-sections, docs/radar.md); spread across the field so none hides another."""
    rows = [EGO, ("car", 62.0, 30.0, 0, 0, 4.0, 1.8), ("near_p", 40.0, -10.0, 0, 0, 0.215, 0.478),
            ("far_p", 46.0, 10.0, 0, 0, 0.215, 0.478), ("near_b", 50.0, 20.0, 0, 0, 1.6, 0.65),
            ("far_b", 58.0, -20.0, 0, 0, 1.6, 0.65)]
    base = snap(rows)
    s = Snapshot(0.0, base.ids, base.pos, base.vel, base.heading, base.length, base.width, base.is_ego,
                 vclass=("passenger", "passenger", "pedestrian", "pedestrian", "bicycle", "bicycle"),
                 is_person=np.array([False, False, True, True, False, False]))
    seen = set(radar(person_detection_prob=1.0).measure(s, ("ego",)).target)
    assert seen == {"car", "near_p", "near_b"}
    assert set(radar().measure(base, ("ego",)).target) == {"car", "near_p", "far_p", "near_b", "far_b"}  # as cars


def test_a_person_is_missed_with_its_own_probability():
    rows = [EGO] + [(f"p{k}", 10.0 + 2.0 * k, 8.0 * (k % 5) - 16.0, 0, 0, 0.215, 0.478) for k in range(10)]
    base = snap(rows)
    s = Snapshot(0.0, base.ids, base.pos, base.vel, base.heading, base.length, base.width, base.is_ego,
                 vclass=("passenger",) + ("pedestrian",) * 10, is_person=np.arange(11) > 0)
    r = radar(person_detection_prob=0.5)
    counts = [len(r.measure(s, ("ego",)).target) for _ in range(200)]
    visible = len(radar(person_detection_prob=1.0).measure(s, ("ego",)).target)
    assert visible >= 8
    assert 0.4 * visible < np.mean(counts) < 0.6 * visible


def _street_snapshot():
    rows = [EGO, ("car", 30.0, 6.0, 0, 0, 4.0, 1.8), ("walker", 20.0, -6.0, 0, 0, 0.215, 0.478),
            ("bike", 25.0, 12.0, 0, 0, 1.6, 0.65)]
    base = snap(rows)
    return Snapshot(0.0, base.ids, base.pos, base.vel, base.heading, base.length, base.width, base.is_ego,
                    vclass=("passenger", "passenger", "pedestrian", "bicycle"),
                    is_person=np.array([False, False, True, False]))


def test_returns_of_persons_and_cyclists_are_labelled_and_the_tracker_keeps_the_label():
    det = radar(person_detection_prob=1.0, memory_s=8.0).measure(_street_snapshot(), ("ego",))
    labels = dict(zip(det.target, det.vru_mask().tolist()))
    assert labels == {"car": False, "walker": True, "bike": True}
    # a world without persons or cyclists: no labels at all (None), every return unlabelled
    plain = radar().measure(snap([EGO, ("car", 30.0, 6.0, 0, 0, 4.0, 1.8)]), ("ego",))
    assert plain.vru is None and plain.vru_mask().tolist() == [False]
    # the memory coasts the walker out of view with its label: the ego turned away, the scan is empty
    r = Radar(RadarParams(person_detection_prob=1.0, range_sigma_m=0.0, speed_sigma_mps=0.0),
              np.random.default_rng(0))
    s0 = _street_snapshot()
    first = r.objects(r.scan(s0, ("ego",)))
    turned = Snapshot(0.2, s0.ids, s0.pos, s0.vel, np.array([np.pi, 0, 0, 0]), s0.length, s0.width, s0.is_ego,
                      vclass=s0.vclass, is_person=s0.is_person)
    kept = r.objects(r.scan(turned, ("ego",)))
    assert first.vru_mask().sum() == 2 and kept.n == 3 and kept.vru_mask().sum() == 2


def test_a_persons_label_is_missed_with_its_own_probability():
    r = radar(person_detection_prob=1.0, vru_label_prob=0.5)
    labelled = [r.measure(_street_snapshot(), ("ego",)).vru_mask().sum() for _ in range(400)]
    assert 0.9 < np.mean(labelled) < 1.1  # two small targets, each labelled with p = 0.5
