"""The formation controller's velocity barrier (formation_shield) against values computed by hand."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.control import formation_shield as sh
from sumo_avoid.core.geometry import footprint_corners

SQUARE = np.array([[[4.0, -1.0], [6.0, -1.0], [6.0, 1.0], [4.0, 1.0]]])


def test_disc_hazard_gap_and_normal():
    # centre (0, 0), disc radius 2: the square's face x = 4 is 4 m away -> gap 2, normal -x
    n, gap = sh.disc_hazards(np.array([[0.0, 0.0]]), np.array([2.0]), SQUARE, SQUARE.mean(axis=1))
    assert gap == pytest.approx(np.array([[2.0]])) and n[0, 0] == pytest.approx([-1.0, 0.0])
    # a centre inside the square: gap = -radius, pushed away from the centroid (5, 0)
    n, gap = sh.disc_hazards(np.array([[4.5, 0.0]]), np.array([2.0]), SQUARE, SQUARE.mean(axis=1))
    assert gap == pytest.approx(np.array([[-2.0]])) and n[0, 0] == pytest.approx([-1.0, 0.0])


def test_footprint_hazard_gap():
    own = footprint_corners(np.array([[0.0, 0.0]]), np.array([0.0]), np.array([4.0]), np.array([2.0]))
    other = footprint_corners(np.array([[0.0, 5.0]]), np.array([0.0]), np.array([4.0]), np.array([2.0]))
    n, gap = sh.footprint_hazards(own, other, np.array([[0.0, 0.0]]), np.array([[0.0, 5.0]]))
    assert gap == pytest.approx(np.array([[3.0]])) and n[0, 0] == pytest.approx([0.0, -1.0])  # side to side, 5 - 2


def test_bounds_by_hand():
    n = np.array([[[-1.0, 0.0]]])
    # static: -k (gap - margin) = -0.5 (2.3 - 0.3) = -1; the other half of a shared pair: -0.5
    assert sh.approach_bounds(n, [[2.3]], 0.3, 0.5) == pytest.approx(np.array([[-1.0]]))
    assert sh.approach_bounds(n, [[2.3]], 0.3, 0.5, share=0.5) == pytest.approx(np.array([[-0.5]]))
    # a hazard moving towards the ego at 2 m/s along -x: v . n >= 2 - 1 = 1 (the ego must back off)
    assert sh.approach_bounds(n, [[2.3]], 0.3, 0.5, hazard_vel=[[-2.0, 0.0]]) == pytest.approx(np.array([[1.0]]))


def test_barrier_changes_only_the_violating_part():
    n = np.array([[[-1.0, 0.0]], [[-1.0, 0.0]]])
    b = np.array([[-1.0], [-1.0]])
    # ego 0 drives at the obstacle at 3 m/s with 1 m/s sideways: approach cut to 1, sideways kept;
    # ego 1 approaches at 0.5 < 1: untouched
    v = sh.barrier(np.array([[3.0, 1.0], [0.5, 2.0]]), n, b)
    assert v == pytest.approx(np.array([[1.0, 1.0], [0.5, 2.0]]))
    # inactive constraints (-inf) change nothing
    assert sh.barrier(np.array([[3.0, 1.0]]), n[:1], np.array([[-np.inf]])) == pytest.approx(np.array([[3.0, 1.0]]))


def test_barrier_two_walls_corner():
    # walls ahead (normal -x) and to the left (normal -y), both allowing 0 approach: a command
    # (2, 2) into the corner ends at (0, 0); (2, -1) keeps its part away from the left wall
    n = np.array([[[-1.0, 0.0], [0.0, -1.0]]] * 2)
    v = sh.barrier(np.array([[2.0, 2.0], [2.0, -1.0]]), n, np.zeros((2, 2)))
    assert v == pytest.approx(np.array([[0.0, 0.0], [0.0, -1.0]]), abs=1e-9)
    # a wedge of 45 deg: x >= 0 side n1 = (-1, 0) with bound 0 and n2 = (-1, -1)/sqrt2 with bound 0:
    # the result satisfies both
    n2 = np.array([[[-1.0, 0.0], [-np.sqrt(0.5), -np.sqrt(0.5)]]])
    v = sh.barrier(np.array([[3.0, 1.0]]), n2, np.zeros((1, 2)))
    assert (np.einsum("ecj,ej->ec", n2, v) >= -1e-9).all()


def test_heading_cap_by_hand():
    # a car heading +x (h = (1, 0)) with a hazard ahead (n = (-1, 0)) that allows 2 m/s of approach:
    # the command (5, 3) drives 5 m/s along the heading -> scaled by 2/5 to (2, 1.2)
    n, b = np.array([[[-1.0, 0.0]]]), np.array([[-2.0]])
    assert sh.heading_cap(np.array([[5.0, 3.0]]), np.array([0.0]), n, b) == pytest.approx(np.array([[2.0, 1.2]]))
    # heading 60 deg at the same hazard: h . n = -0.5, sigma <= 4; command along the heading at 6 m/s -> 4
    v = 6.0 * np.array([[0.5, np.sqrt(0.75)]])
    assert sh.heading_cap(v, np.array([np.pi / 3]), n, b) == pytest.approx(v * 4.0 / 6.0)
    # a hazard behind (h . n > 0): untouched; one faced at an allowed approach of 0.1 m/s: the creep
    # speed 0.5 m/s (to turn away); one faced within the margin (b >= 0): 0
    assert sh.heading_cap(np.array([[5.0, 0.0]]), np.array([np.pi]), n, b) == pytest.approx(np.array([[5.0, 0.0]]))
    assert sh.heading_cap(np.array([[5.0, 0.0]]), np.array([0.0]), n, np.array([[-0.1]])) == pytest.approx(
        np.array([[0.5, 0.0]]))
    assert sh.heading_cap(np.array([[5.0, 0.0]]), np.array([0.0]), n, np.array([[1.0]])) == pytest.approx(
        np.zeros((1, 2)))
