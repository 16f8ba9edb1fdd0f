"""The reference simulator's noise processes (sumo_avoid.core.noise): hand-computed steps and the
stationary spread of the GPS walk against its closed form."""
from __future__ import annotations

import math

import numpy as np
import pytest

from sumo_avoid.core.noise import DampedRandomWalk, velocity_kick


class _Fixed:
    """A stand-in generator whose normal() returns the given values (only for pinning the maths)."""

    def __init__(self, *values):
        self.values = list(values)

    def normal(self, loc, scale, size):
        return loc + scale * np.asarray(self.values.pop(0), float).reshape(size)


def test_damped_random_walk_two_steps_by_hand():
    # sigma 0.005, lambda 0.1, dt 0.2: sqrt(2 lambda dt sigma) = sqrt(0.0002) = 0.0141421356;
    # k = sqrt(2 lambda sigma) / 3 = sqrt(0.001) / 3 = 0.0105409255
    w = DampedRandomWalk(0.005, 0.1, _Fixed([[1.0, -2.0]], [[0.5, 0.0]]))
    x, u = w.step(["a"], 0.2)
    np.testing.assert_allclose(u, [[0.0141421356, -0.0282842712]], rtol=1e-8)
    np.testing.assert_allclose(x, [[0.0028284271, -0.0056568542]], rtol=1e-8)
    # step 2: u2 = u1 + 0.5*0.0141421356 - k*x1*0.2 - 0.1*0.2*u1
    x, u = w.step(["a"], 0.2)
    u2x = 0.0141421356 + 0.0070710678 - 0.0105409255 * 0.0028284271 * 0.2 - 0.02 * 0.0141421356
    u2y = -0.0282842712 + 0.0 - 0.0105409255 * -0.0056568542 * 0.2 - 0.02 * -0.0282842712
    np.testing.assert_allclose(u, [[u2x, u2y]], rtol=1e-8)
    np.testing.assert_allclose(x, [[0.0028284271 + 0.2 * u2x, -0.0056568542 + 0.2 * u2y]], rtol=1e-8)


def test_damped_random_walk_keys_are_independent_and_new_keys_start_at_zero():
    w = DampedRandomWalk(0.005, 0.1, _Fixed([[1.0, 1.0]], [[0.0, 0.0], [2.0, 2.0]]))
    w.step(["a"], 0.2)
    x, u = w.step(["a", "b"], 0.2)
    np.testing.assert_allclose(u[1], [2.0 * 0.0141421356] * 2, rtol=1e-8)  # b: first step from 0
    assert u[0, 0] == pytest.approx(0.0141421356 * (1 - 0.02) - 0.0105409255 * 0.0028284271 * 0.2)


def test_gps_walk_stationary_spread_matches_closed_form():
    """x'' + lambda x' + k x = sqrt(2 lambda sigma) w: var(u) = sigma, var(x) = sigma / k.
    sigma 0.005, lambda 0.1: sd(u) = 0.0707 m/s, sd(x) = sqrt(0.005 / 0.0105409) = 0.6887 m."""
    w = DampedRandomWalk(0.005, 0.1, np.random.default_rng(1))
    keys = list(range(4000))
    for _ in range(2000):  # 400 s: the slowest mode decays in ~20 s
        x, u = w.step(keys, 0.2)
    assert x.std() == pytest.approx(math.sqrt(0.005 / (math.sqrt(0.001) / 3)), rel=0.05)
    assert u.std() == pytest.approx(math.sqrt(0.005), rel=0.05)


def test_velocity_kick_spread():
    k = velocity_kick(np.random.default_rng(0), 0.2, 0.2, 200_000)
    assert k.shape == (200_000, 2)
    assert k.std() == pytest.approx(math.sqrt(2 * 0.2 * 0.2), rel=0.01)  # 0.2828 m/s per step
    assert abs(k.mean()) < 3 * 0.2828 / math.sqrt(k.size)


def test_damped_random_walk_follows_its_keys_when_their_order_changes():
    """The rows of the last call's keys are kept (a flock's keys rarely change); keys given in another order, or
    the same list again, still step each key's own walk: b's second step is a's first, mirrored."""
    w = DampedRandomWalk(0.005, 0.1, _Fixed([[1.0, 1.0], [0.0, 0.0]], [[1.0, 1.0], [0.0, 0.0]],
                                           [[0.0, 0.0], [0.0, 0.0]]))
    keys = ["a", "b"]
    x1, u1 = w.step(keys, 0.2)  # a kicked, b not
    x2, u2 = w.step(["b", "a"], 0.2)  # now b (first row) kicked, a not: rows follow the keys
    np.testing.assert_allclose(u2[0], u1[0], rtol=1e-12)  # b's first kick is a's first kick
    assert u2[1, 0] == pytest.approx(0.0141421356 * (1 - 0.02) - 0.0105409255 * 0.0028284271 * 0.2)
    x3, u3 = w.step(keys, 0.2)  # the first list object again: a's third step, b's second
    assert u3[1, 0] == pytest.approx(0.0141421356 * (1 - 0.02) - 0.0105409255 * 0.0028284271 * 0.2)
