"""SPEC §2 attractive and repulsive fields, pinned to hand-computed values."""
import numpy as np
import pytest

from sumo_avoid.control.apf import attraction, repulsion


def test_attraction_quadratic_inside_d():
    # q = (3, 4), goal at origin, rho = 5 <= d = 10, K = 2: U = 0.5*2*25 = 25, F = -2*(3,4)
    U, F = attraction([[3.0, 4.0]], [0.0, 0.0], k_att=2.0, d=10.0)
    assert U[0] == pytest.approx(25.0)
    assert F[0] == pytest.approx([-6.0, -8.0])


def test_attraction_capped_beyond_d():
    # rho = 50 > d = 10, K = 2: U = 10*2*50 - 0.5*2*100 = 900; |F| = d K = 20 along -(q - goal)/rho
    U, F = attraction([[30.0, 40.0]], [0.0, 0.0], k_att=2.0, d=10.0)
    assert U[0] == pytest.approx(900.0)
    assert F[0] == pytest.approx([-12.0, -16.0])
    # continuity at rho = d: both branches give 0.5 K d^2 = 100
    U1, _ = attraction([[10.0, 0.0]], [0.0, 0.0], 2.0, 10.0)
    assert U1[0] == pytest.approx(100.0)


def test_repulsion_inside_and_outside_influence():
    # rho = 2, rho0 = 4, K = 8: (1/2 - 1/4) = 0.25; U = 0.5*8*0.0625 = 0.25; |F| = 8*0.25/4 = 0.5
    U, F = repulsion(np.array([2.0, 5.0]), np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([4.0, 4.0]), 8.0)
    assert U == pytest.approx([0.25, 0.0])
    assert F[0] == pytest.approx([0.5, 0.0])
    assert F[1] == pytest.approx([0.0, 0.0])


def test_force_is_minus_gradient_of_potential():
    # numerical check of F = -dU/drho for the repulsion magnitude at rho = 1.5, rho0 = 3, K = 5
    h = 1e-6
    U = lambda r: repulsion(np.array([r]), np.array([[1.0, 0.0]]), np.array([3.0]), 5.0)[0][0]
    _, F = repulsion(np.array([1.5]), np.array([[1.0, 0.0]]), np.array([3.0]), 5.0)
    assert F[0, 0] == pytest.approx(-(U(1.5 + h) - U(1.5 - h)) / (2 * h), rel=1e-5)
