"""The kinematic car, pinned to hand-computed values."""
import math

import numpy as np
import pytest

from sumo_avoid.actuation.kinematic import KinematicParams, actuate, wrap_angle

LIM = KinematicParams(max_accel_mps2=2.0, max_decel_mps2=5.0, max_lat_accel_mps2=4.0, max_yaw_rate_radps=0.5,
                      min_turn_radius_m=5.0, max_reverse_speed_mps=2.0)


def test_acceleration_and_braking_are_capped():
    # wants 20 m/s from 10 m/s: +2 m/s^2 * 0.1 s = 10.2 m/s; moves 0.1 * 10.2 = 1.02 m along +x
    m = actuate([[0, 0]], [0.0], [10.0], [[20.0, 0.0]], LIM, 0.1)
    assert m.speed[0] == pytest.approx(10.2)
    assert m.pos[0] == pytest.approx([1.02, 0.0])
    # wants 0 from 10: -5 * 0.1 -> 9.5 m/s
    m = actuate([[0, 0]], [0.0], [10.0], [[0.0, 0.0]], LIM, 0.1)
    assert m.speed[0] == pytest.approx(9.5)
    assert m.heading[0] == 0.0


def test_yaw_rate_limited_by_lateral_acceleration():
    # at 10 m/s (target 10 * cos 90deg = 0 -> brakes to 9.5; mean speed 9.75):
    # yaw <= min(0.5, 4/9.75 = 0.41026, 9.75/5 = 1.95) = 0.41026 rad/s -> 0.041026 rad in 0.1 s
    m = actuate([[0, 0]], [0.0], [10.0], [[0.0, 10.0]], LIM, 0.1)
    assert m.heading[0] == pytest.approx(0.1 * 4.0 / 9.75)
    assert m.speed[0] == pytest.approx(9.5)


def test_no_turning_on_the_spot():
    # stopped, desired velocity 90 deg to the left: forward target 5 cos 90deg = 0, yaw <= v/R = 0
    m = actuate([[0, 0]], [0.0], [0.0], [[0.0, 5.0]], KinematicParams(max_reverse_speed_mps=0.0), 0.1)
    assert m.heading[0] == 0.0 and m.speed[0] == pytest.approx(0.0, abs=1e-12)


def test_reverses_when_stopped_and_target_behind():
    # stopped, desired velocity straight back (180 deg off): reverse at min(|v| |cos|, 2) = 2 m/s,
    # but acceleration caps it at -2 m/s^2 * 0.1 s = -0.2 m/s; moves -0.02 m
    m = actuate([[0, 0]], [0.0], [0.0], [[-5.0, 0.0]], LIM, 0.1)
    assert m.speed[0] == pytest.approx(-0.2)
    assert m.pos[0] == pytest.approx([-0.02, 0.0])


def test_no_direct_switch_forward_to_reverse():
    m = actuate([[0, 0]], [0.0], [0.1], [[-5.0, 0.0]], LIM, 0.1)
    assert m.speed[0] == 0.0


def test_wrap_angle():
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(-3 * math.pi / 2) == pytest.approx(math.pi / 2)


def test_vectorised_over_egos():
    m = actuate(np.zeros((3, 2)), np.zeros(3), np.full(3, 5.0), [[5, 0], [10, 0], [0, 0]], LIM, 0.1)
    assert m.speed == pytest.approx([5.0, 5.2, 4.5])


def test_each_actuator_declares_the_steering_limits_controllers_plan_with():
    """The kinematic car plans with its turning radius and yaw-rate limit; relaxation with none."""
    from sumo_avoid.actuation import ACTUATORS
    from sumo_avoid.actuation.relaxation import RelaxationParams

    assert ACTUATORS["kinematic"].factory.steering(LIM) == (5.0, 0.5, 0.0)
    assert ACTUATORS["relaxation"].factory.steering(RelaxationParams()) == (0.0, math.inf, 0.0)


def test_a_stop_wish_with_a_direction_brakes_and_steers_that_way():
    # moving at 5 m/s, heading 0; the wish: stop (1e-4 m/s, below STOP_WISH_MPS), facing 0.2 rad left.
    # Full braking: 5 - 8 * 0.1 = 4.2 m/s; the heading turns by the yaw limit at the mean speed 4.6 m/s:
    # min(0.8, 4 / 4.6, 4.6 / 4.25) * 0.1 = 0.08 rad (a zero wish keeps the heading: the car goes on straight)
    from sumo_avoid.actuation.kinematic import STOP_WISH_MPS

    wish = 0.1 * STOP_WISH_MPS * np.array([[math.cos(0.2), math.sin(0.2)]])
    m = actuate([[0.0, 0.0]], [0.0], [5.0], wish, KinematicParams(), 0.1)
    assert m.speed[0] == pytest.approx(4.2)
    assert m.heading[0] == pytest.approx(0.08)
    assert actuate([[0.0, 0.0]], [0.0], [5.0], [[0.0, 0.0]], KinematicParams(), 0.1).heading[0] == 0.0
    # standing, it neither moves nor turns (nor reverses for a wish behind it)
    for ang in (0.2, 3.0):
        m = actuate([[0.0, 0.0]], [0.0], [0.0], 1e-4 * np.array([[math.cos(ang), math.sin(ang)]]), KinematicParams(), 0.1)
        assert (m.speed[0], m.heading[0], *m.pos[0]) == (0.0, 0.0, 0.0, 0.0)


def test_relaxation_holds_each_egos_velocity_and_forgets_a_removed_one():
    """The relaxation actuator hands the next snapshot the velocities it set (SUMO keeps a moved vehicle's speed
    along its heading only): its egos' rows change, every other row and field stays; a removed ego is SUMO's again."""
    import types

    from sumo_avoid.actuation.relaxation import RelaxationActuator, RelaxationParams
    from sumo_avoid.core.snapshot import Snapshot
    from sumo_avoid.core.types import Observation

    ctx = types.SimpleNamespace(step_s=0.5, rng=lambda k: np.random.default_rng(k))
    act = RelaxationActuator(RelaxationParams(tau_s=1.0, max_accel_mps2=100.0), ctx)
    snap = Snapshot(0.0, ("a", "car", "b"), np.array([[0.0, 0.0], [5.0, 5.0], [10.0, 0.0]]),
                    np.array([[1.0, 0.0], [3.0, 0.0], [0.0, 2.0]]), np.zeros(3), np.full(3, 4.0), np.full(3, 2.0),
                    np.array([True, False, True]))
    obs = Observation(snap, ("a", "b"), np.array([0, 2]), np.array([1.0, 2.0]))
    act.step(obs, np.array([[3.0, 0.0], [0.0, 4.0]]))  # v += (v_des - v) dt / tau: a (2, 0), b (0, 3)
    held = act.held(snap)
    np.testing.assert_allclose(held.vel, [[2.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    assert held.ids == snap.ids and held.pos is snap.pos and held.index == snap.index and snap.vel[0, 0] == 1.0
    assert not held.vel.flags.writeable
    act.remove_ego("a")  # taken out (its goal): its row is SUMO's again, b's is still held
    np.testing.assert_allclose(act.held(snap).vel, [[1.0, 0.0], [3.0, 0.0], [0.0, 3.0]])


@pytest.mark.parametrize("axle, rear_y", [(1.325, -0.05713), (0.0, -0.16301)], ids=["rear_axle", "centre"])
def test_the_car_turns_about_its_rear_axle(axle, rear_y):
    # 5 m/s, asked to go left: target 5 cos 90deg = 0 -> brakes 8 * 0.1 to 4.2 m/s, mean 4.6;
    # yaw <= min(0.8, 4/4.6, 4.6/sqrt(4.25^2 - 1.325^2) = 1.139) = 0.8 rad/s -> 0.08 rad; the axle 1.325 m behind
    # the centre moves 0.42 m along the mid heading 0.04: centre (0.42 cos 0.04 + 1.325 (cos 0.08 - 1), 0.42 sin 0.04
    # + 1.325 sin 0.08) = (0.415426, 0.122682). The rear bumper (2.25 m behind the centre) swings 0.057 m to the
    # right; turning about the centre, 0.163 m
    lim = KinematicParams(rear_axle_m=axle)
    m = actuate([[0.0, 0.0]], [0.0], [5.0], [[0.0, 5.0]], lim, 0.1)
    assert m.heading[0] == pytest.approx(0.08)
    if axle:
        assert m.pos[0] == pytest.approx([0.415426306, 0.122682490])
    else:
        assert m.pos[0] == pytest.approx([0.419664045, 0.016795520])
    rear = m.pos[0] - 2.25 * np.array([math.cos(0.08), math.sin(0.08)])
    assert rear[1] == pytest.approx(rear_y, abs=5e-5)
