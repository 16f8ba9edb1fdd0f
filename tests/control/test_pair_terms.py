"""The compiled flocking pair terms against the numpy terms (repulsion, friction): equal within 1e-12 relative
(two implementations are not compared bit for bit: README, the determinism contract)."""
import numpy as np
import pytest

from sumo_avoid.control.flocking.terms import FlockingParams, friction, neighbour_pairs, pair_terms, repulsion


@pytest.mark.parametrize("n,tree", [(5, False), (60, False), (150, True)])
def test_pair_terms_are_the_numpy_terms(n, tree):
    rng = np.random.default_rng(n)
    p = FlockingParams(preset="paper_v4")
    pos = rng.uniform(0, 250.0 * np.sqrt(n / 100), (n, 2))
    pos[1] = pos[0]  # a coincident pair: no direction
    vel = rng.normal(0, 3.0, (n, 2))
    vel[3] = vel[2]
    i, j, r = neighbour_pairs(pos, pos, p.r_c_m, use_tree=tree)
    rep, fric = pair_terms(pos, pos, vel, vel, i, j, r, p, n)
    np.testing.assert_allclose(rep, repulsion(pos, pos, i, j, r, p, n), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(fric, friction(vel, vel, i, j, r, p, n), rtol=1e-12, atol=1e-12)


def test_pair_terms_by_hand():
    """Two agents 10 m apart on x, the second 3 m/s faster along x. Repulsion on the first: p_rep (r0 - 10) = 0.13 * 15.6
    = 2.028 m/s away (-x). Friction: D(10 - 85.3) = 0 < v_frict 0.63, so -0.05 (3 - 0.63) = -0.1185 along v_1 - v_2 (-x)."""
    p = FlockingParams(preset="paper_v4")
    pos = np.array([[0.0, 0.0], [10.0, 0.0]])
    vel = np.array([[1.0, 0.0], [4.0, 0.0]])
    rep, fric = pair_terms(pos, pos, vel, vel, np.array([0]), np.array([1]), np.array([10.0]), p, 2)
    assert rep[0] == pytest.approx([-2.028, 0.0]) and rep[1].tolist() == [0.0, 0.0]
    assert fric[0] == pytest.approx([0.1185, 0.0]) and fric[1].tolist() == [0.0, 0.0]


def test_one_tree_for_the_same_points_gives_the_same_pairs():
    from scipy.spatial import cKDTree

    pos = np.random.default_rng(1).uniform(0, 300, (200, 2))
    m = cKDTree(pos).sparse_distance_matrix(cKDTree(pos.copy()), 80.0, output_type="ndarray")
    keep = m["i"] != m["j"]
    i, j, r = neighbour_pairs(pos, pos.copy(), 80.0, use_tree=True)
    assert np.array_equal(i, m["i"][keep]) and np.array_equal(j, m["j"][keep])
    np.testing.assert_allclose(r, m["v"][keep], rtol=1e-12)


@pytest.mark.parametrize("n,moved", [(150, False), (150, True), (700, True)])
def test_one_pass_tree_terms_are_the_pairs_terms(n, moved):
    """neighbour_terms(use_tree=True) (search and sums in one compiled pass) against neighbour_pairs + pair_terms
    on the same points: the neighbours' positions as received (moved: V2V noise) or the same as the egos'."""
    from sumo_avoid.control.flocking.terms import neighbour_terms

    rng = np.random.default_rng(n + moved)
    p = FlockingParams(preset="paper_v4")
    pos = rng.uniform(0, 250.0 * np.sqrt(n / 100), (n, 2))
    pos[1] = pos[0]
    vel = rng.normal(0, 3.0, (n, 2))
    nb = pos + rng.normal(0, 0.5, pos.shape) if moved else pos.copy()
    nv = vel + rng.normal(0, 0.1, vel.shape) if moved else vel.copy()
    i, j, r = neighbour_pairs(pos, nb, p.r_c_m, use_tree=True)
    want = pair_terms(pos, nb, vel, nv, i, j, r, p, n)
    got = neighbour_terms(pos, nb, vel, nv, p, use_tree=True)
    for a, b in zip(got, want):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_one_pass_tree_terms_by_hand():
    """The hand-computed pair above (10 m apart, repulsion 2.028 m/s, friction 0.1185 m/s), with a third agent
    exactly r_c = 80 m from the first (a neighbour: D(80 - 85.3) = 0, r0_rep 15.6 m, so only friction, and
    with equal velocities none) and a fourth 80.001 m away (none): the first agent's terms are the pair's."""
    from sumo_avoid.control.flocking.terms import neighbour_terms

    p = FlockingParams(preset="paper_v4")
    pos = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 80.0], [-80.001, 0.0]])
    vel = np.array([[1.0, 0.0], [4.0, 0.0], [1.0, 0.0], [-30.0, 0.0]])
    rep, fric = neighbour_terms(pos, pos, vel, vel, p, use_tree=True)
    assert rep[0] == pytest.approx([-2.028, 0.0]) and fric[0] == pytest.approx([0.1185, 0.0])
    assert rep[3].tolist() == [0.0, 0.0] and fric[3].tolist() == [0.0, 0.0]  # nobody within 80 m of it
