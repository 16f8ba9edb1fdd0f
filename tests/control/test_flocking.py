"""Flocking controller (SPEC §1 eq. 1-10): each velocity term against hand-computed values, the
presets, and small two-vehicle / wall behaviours integrated with the relaxation actuator."""
from __future__ import annotations

import math

import numpy as np
import pytest

from sumo_avoid.actuation.relaxation import relaxation_step
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.control.flocking.terms import (
    PRESETS,
    FlockingParams,
    combine,
    friction,
    neighbour_pairs,
    polygon_shills,
    preset,
    repulsion,
    segment_shills,
    shill,
)
from sumo_avoid.control.flocking.flocking import FlockingController
from sumo_avoid.metrics.basic import braking_curve_D as D
from sumo_avoid.road.walls import square

P4 = preset("paper_v4")


def test_registry_and_presets_hold_table3():
    assert (CONTROLLERS["flocking"].factory, CONTROLLERS["flocking"].params) == (FlockingController, FlockingParams)
    p6, p8 = preset("paper_v6"), preset("paper_v8")
    assert (P4.r0_rep_m, P4.p_rep_ps, P4.r0_frict_m, P4.c_frict, P4.v_frict_mps) == (25.6, 0.13, 85.3, 0.05, 0.63)
    assert (p6.p_frict_ps, p6.a_frict_mps2, p6.r0_shill_m, p6.v_shill_mps) == (5.32, 9.94, 0.5, 19.7)
    assert (p8.p_shill_ps, p8.a_shill_mps2, p8.v_flock_mps, p8.r0_rep_m) == (8.12, 4.18, 8.0, 52.9)
    # TOML-style: preset fills what is left at default, explicit values win
    q = FlockingParams(preset="paper_v8", r_c_m=60.0, p_rep_ps=0.5)
    assert (q.r0_rep_m, q.r_c_m, q.p_rep_ps) == (52.9, 60.0, 0.5)
    with pytest.raises(ValueError):
        FlockingParams(preset="paper_v5")
    with pytest.raises(ValueError):
        FlockingParams(speed_rule="clip")
    assert set(PRESETS) == {"paper_v4", "paper_v6", "paper_v8"}


def test_neighbour_pairs_dense_equals_kdtree_and_includes_exactly_rc():
    pos = np.array([[0.0, 0.0], [80.0, 0.0], [160.0, 0.1], [0.0, 30.0]])
    for tree in (False, True):
        i, j, r = neighbour_pairs(pos, pos, 80.0, use_tree=tree)
        got = sorted(zip(i.tolist(), j.tolist()))
        assert got == [(0, 1), (0, 3), (1, 0), (3, 0)]  # r exactly r_c counts; 1-2 is 80.00006 m
    rng = np.random.default_rng(0)
    pos = rng.uniform(0, 200, (150, 2))
    a = neighbour_pairs(pos, pos, 40.0, use_tree=False)
    b = neighbour_pairs(pos, pos, 40.0, use_tree=True)
    ka = sorted(zip(a[0].tolist(), a[1].tolist()))
    kb = sorted(zip(b[0].tolist(), b[1].tolist()))
    assert ka == kb


def test_repulsion_hand_values():
    p = FlockingParams(r0_rep_m=25.0, p_rep_ps=0.2)
    pos = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 25.0]])  # 0-2 exactly at r0_rep: no force
    i, j, r = neighbour_pairs(pos, pos, 80.0)
    v = repulsion(pos, pos, i, j, r, p, 3)
    # 0.2 * (25 - 10) = 3 m/s away from each other along x
    np.testing.assert_allclose(v, [[-3.0, 0.0], [3.0, 0.0], [0.0, 0.0]], atol=1e-12)


def test_friction_hand_values():
    p = FlockingParams(c_frict=0.1, v_frict_mps=0.5, r0_frict_m=10.0, a_frict_mps2=2.0, p_frict_ps=1.0)
    pos = np.array([[0.0, 0.0], [12.0, 0.0]])  # r - r0 = 2: D = r p = 2 (2*1 = 2 >= a/p = 2 -> sqrt branch)
    assert D(2.0, 2.0, 1.0) == pytest.approx(math.sqrt(2 * 2 * 2 - 4))  # = 2
    vel = np.array([[5.0, 0.0], [0.0, 0.0]])  # v_ij = 5 > max(0.5, 2) = 2
    i, j, r = neighbour_pairs(pos, pos, 80.0)
    v = friction(vel, vel, i, j, r, p, 2)
    np.testing.assert_allclose(v, [[-0.1 * 3.0, 0.0], [0.1 * 3.0, 0.0]], atol=1e-12)  # pulls together
    # below the slack: nothing
    vel = np.array([[0.4, 0.0], [0.0, 0.0]])
    pos = np.array([[0.0, 0.0], [5.0, 0.0]])  # r < r0_frict: D = 0, v_frictmax = v_frict = 0.5
    i, j, r = neighbour_pairs(pos, pos, 80.0)
    np.testing.assert_allclose(friction(vel, vel, i, j, r, p, 2), 0.0)
    vel = np.array([[0.0, 1.5], [0.0, 0.0]])  # 1.5 - 0.5 = 1 -> -0.1 along +y for vehicle 0
    np.testing.assert_allclose(friction(vel, vel, i, j, r, p, 2), [[0.0, -0.1], [0.0, 0.1]], atol=1e-12)


def test_wall_shill_hand_values_and_outside():
    p = FlockingParams(v_shill_mps=6.0, r0_shill_m=0.0, a_shill_mps2=2.0, p_shill_ps=1.0)
    a, b, n = np.array([[0.0, 0.0]]), np.array([[100.0, 0.0]]), np.array([[0.0, 1.0]])  # floor, inward +y
    pos = np.array([[50.0, 4.0], [50.0, -3.0], [50.0, 30.0]])
    vel = np.array([[0.0, -4.0], [0.0, 0.0], [0.0, -4.0]])
    dist, nrm = segment_shills(pos, a, b, n, outside=np.array([False, True, False]))
    np.testing.assert_allclose(dist[:, 0], [4.0, 0.0, 30.0])
    v = np.stack([shill(vel[k:k + 1], dist[k:k + 1], nrm[k:k + 1], p)[0] for k in range(3)])
    # vehicle 0: v_s - v_i = (0, 10), D(4, 2, 1) = sqrt(16 - 4) = 3.4641 -> (0, 10 - 3.4641)
    np.testing.assert_allclose(v[0], [0.0, 10.0 - math.sqrt(12.0)], atol=1e-12)
    np.testing.assert_allclose(v[1], [0.0, 6.0], atol=1e-12)  # outside: D = 0, full correction
    np.testing.assert_allclose(v[2], [0.0, 0.0], atol=1e-12)  # D(30) = sqrt(116) > 10: no term
    # the compiled walls' term (the controller's) gives the same hand values, each vehicle alone or all at once
    from sumo_avoid.control.flocking.terms import wall_shills

    got = wall_shills(pos, vel, a, b, n, np.array([False, True, False]), p)
    np.testing.assert_allclose(got, [[0.0, 10.0 - math.sqrt(12.0)], [0.0, 6.0], [0.0, 0.0]], atol=1e-12)


def test_polygon_obstacle_shill_directions():
    box = np.array([[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]])
    pos = np.array([[15.0, 5.0], [13.0, 14.0], [8.0, 5.0]])
    dist, nrm = polygon_shills(pos, box)
    np.testing.assert_allclose(dist[:, 0], [5.0, 5.0, 0.0])
    np.testing.assert_allclose(nrm[0, 0], [1.0, 0.0], atol=1e-12)  # face: normal
    np.testing.assert_allclose(nrm[1, 0], [0.6, 0.8], atol=1e-12)  # corner: radial
    np.testing.assert_allclose(nrm[2, 0], [1.0, 0.0], atol=1e-12)  # inside: out through the nearest face


def test_speed_rules():
    v = np.array([[30.0, 40.0], [0.3, 0.4]])
    np.testing.assert_allclose(combine(v, FlockingParams(v_max_mps=8.0)), [[4.8, 6.4], [0.3, 0.4]])
    np.testing.assert_allclose(combine(v, FlockingParams(v_flock_mps=4.0, speed_rule="rescale")),
                               [[2.4, 3.2], [2.4, 3.2]])


def test_desired_is_the_sum_of_the_terms():
    ctl = FlockingController(FlockingParams())
    ctl.set_walls(square((0, 0), 250.0))
    rng = np.random.default_rng(3)
    pos = rng.uniform(5, 245, (12, 2))
    vel = rng.normal(0, 3, (12, 2))
    p = ctl.p
    i, j, r = neighbour_pairs(pos, pos, p.r_c_m)
    a, b, n = ctl._walls
    dist, nrm = segment_shills(pos, a, b, n, np.zeros(12, bool))
    u = vel / np.hypot(*vel.T)[:, None]
    want = combine(p.v_flock_mps * u + repulsion(pos, pos, i, j, r, p, 12) + friction(vel, vel, i, j, r, p, 12)
                   + shill(vel, dist, nrm, p), p)
    got = ctl.desired(pos, vel, np.zeros(12), pos, vel)
    np.testing.assert_allclose(got, want, atol=1e-12)


def _simulate(ctl, pos, vel, steps, dt=0.2):
    heading = np.arctan2(vel[:, 1], vel[:, 0])
    for _ in range(steps):
        v_des = ctl.desired(pos, vel, heading, pos, vel)
        pos, vel, heading, _ = relaxation_step(pos, vel, heading, v_des, 1.0, 6.0, dt)
    return pos, vel


def test_two_vehicles_repel_below_r0_rep():
    ctl = FlockingController(preset("paper_v4"))
    pos = np.array([[100.0, 100.0], [105.0, 100.0]])
    vel = np.array([[0.0, 4.0], [0.0, 4.0]])
    pos1, _ = _simulate(ctl, pos, vel, 25)
    assert np.hypot(*(pos1[0] - pos1[1])) > 15.0  # pushed apart from 5 m


def test_two_vehicles_align():
    ctl = FlockingController(FlockingParams(c_frict=0.3, r0_rep_m=5.0))
    pos = np.array([[0.0, 0.0], [40.0, 0.0]])
    vel = np.array([[4.0, 0.0], [0.0, 4.0]])
    _, vel1 = _simulate(ctl, pos, vel, 100)
    # |v_i - v_j| falls from 5.7 m/s to the slack v_frict (0.63 m/s) the term leaves alone
    assert np.hypot(*(vel1[0] - vel1[1])) < ctl.p.v_frict_mps + 0.05
    cos = vel1[0] @ vel1[1] / np.hypot(*vel1[0]) / np.hypot(*vel1[1])
    assert cos > 0.98


def test_wall_turns_a_vehicle_back():
    ctl = FlockingController(preset("paper_v4"))
    ctl.set_walls(square((0, 0), 250.0))
    pos = np.array([[200.0, 125.0]])
    vel = 4.0 * np.array([[math.cos(0.5), math.sin(0.5)]])  # towards the east wall, 29 deg off its normal
    heading = np.full(1, 0.5)
    xmax = 0.0
    for _ in range(300):
        v_des = ctl.desired(pos, vel, heading, pos, vel)
        pos, vel, heading, _ = relaxation_step(pos, vel, heading, v_des, 1.0, 6.0, 0.2)
        xmax = max(xmax, pos[0, 0])
    assert xmax < 250.0
    assert vel[0, 0] < 0.0  # going back west


def test_radar_flock_drops_v2v_members_and_keeps_each_egos_own_returns():
    """sensor = "radar": ego a sees member b (dropped: b is known over V2V) and car c; ego b sees
    nothing ahead. Only a feels c's shill (owner mask), and c's box is where the radar put it."""
    from sumo_avoid.core.snapshot import Snapshot
    from sumo_avoid.core.types import Observation
    from sumo_avoid.sensing.perception import radar_obstacles
    from sumo_avoid.sensing.radar import Radar, RadarParams

    ids = ("a", "b", "c")
    pos = np.array([[0.0, 0.0], [15.0, 0.0], [30.0, 12.0]])
    vel = np.array([[10.0, 0.0], [10.0, 0.0], [10.0, 0.0]])
    snap = Snapshot(0.0, ids, pos, vel, np.zeros(3), np.full(3, 4.5), np.full(3, 1.8), [True, True, False])
    det = Radar(RadarParams(range_sigma_m=0, speed_sigma_mps=0, angular_resolution_deg=0, fov_deg=60),
                np.random.default_rng(0)).scan(snap, ["a", "b"])
    assert sorted(det.target) == ["b", "c"]  # a sees b and c; c is outside b's 60 degree beam
    obs = Observation(snap, ("a", "b"), np.array([0, 1]), np.zeros(2), detections=(det,))
    corners, v, owner = radar_obstacles(obs, pos[:2], 4.0)
    assert owner.tolist() == [0]  # only a's return of c is left
    centre = corners[0].mean(axis=0)
    assert np.hypot(*(centre - pos[2])) < 1.0  # the assumed box lands on c (radar: c's nearest corner)
    np.testing.assert_allclose(v, [[10.0, 0.0]], atol=1e-9)
