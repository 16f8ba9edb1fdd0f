"""The formation controller's velocity barrier (formation_shield) against values computed by hand."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.control.formation import shield as sh
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


def test_member_discs_by_hand():
    # members 5 m apart along x, half diagonals 2 and 1.5: gap 5 - 3.5 = 1.5, normals along -+x; self 5 - 4 = -4
    # (masked by the caller)
    pos = np.array([[0.0, 0.0], [5.0, 0.0]])
    n, gap = sh.member_disc_hazards(pos, np.array([2.0, 1.5]), pos)
    assert gap[0, 1] == pytest.approx(1.5) and gap[1, 0] == pytest.approx(1.5)
    assert n[0, 1] == pytest.approx([-1.0, 0.0]) and n[1, 0] == pytest.approx([1.0, 0.0])
    # two cars side by side 3 m apart at right angles: footprints 1.1 m apart, discs overlap (3 - 2 x 2.19)
    m = sh.Members(pos=np.array([[0.0, 0.0], [0.0, 3.0]]), heading=np.array([0.0, np.pi / 2]),
                   length=np.array([4.0, 4.0]), width=np.array([1.8, 1.8]), nb_pos=np.array([[0.0, 0.0], [0.0, 3.0]]),
                   nb_vel=np.zeros((2, 2)))
    none = (np.zeros((0, 4, 2)), np.zeros((2, 0), bool), np.zeros(0, bool), np.zeros((0, 2)))
    # member 0 drives towards member 1 at 1 m/s: footprints 3 - 0.9 - 2 = 0.1 m apart, within the margin:
    # it must back off at half of 0.5 x (0.3 - 0.1) = 0.05 m/s; discs (gap 3 - 2 r = -1.39 m): at 0.42 m/s
    v_fp = sh.apply(np.array([[0.0, 1.0], [0.0, 0.0]]), m, *none, 0.3, 0.5, member_disc=False)
    v_disc = sh.apply(np.array([[0.0, 1.0], [0.0, 0.0]]), m, *none, 0.3, 0.5, member_disc=True)
    r = 0.5 * np.hypot(4.0, 1.8)
    assert v_fp[0] == pytest.approx([0.0, -0.25 * (0.3 - 0.1)], abs=1e-9)
    assert v_disc[0] == pytest.approx([0.0, -0.25 * (2 * r - 3.0 + 0.3)], abs=1e-9)


def test_slide_only_where_it_keeps_every_constraint():
    # one hazard ahead (n = (-1, 0), bound 0): (2, 0) is cut to 0 and slides 2 to the left of n: (0, -2)
    n1 = np.array([[[-1.0, 0.0]]])
    assert sh.barrier(np.array([[2.0, 0.0]]), n1, np.zeros((1, 1)), slide=1.0) == pytest.approx(np.array([[0.0, -2.0]]))
    # a second hazard on that side (n = (0, 1), bound 0): the slide would drive into it, so the plain
    # correction (0, 0) stands; a command with room, (2, 1) -> (0, 1), keeps it too
    n2 = np.array([[[-1.0, 0.0], [0.0, 1.0]]])
    assert sh.barrier(np.array([[2.0, 0.0]]), n2, np.zeros((1, 2)), slide=1.0) == pytest.approx(np.zeros((1, 2)))
    assert sh.barrier(np.array([[2.0, 1.0]]), n2, np.zeros((1, 2)), slide=1.0) == pytest.approx(np.array([[0.0, 1.0]]))
