"""Cuckoo search with Lévy flights (SPEC §3): Mantegna's sigma_u by hand, the step distribution's
tail, abandonment counts, and the ask/tell optimiser's determinism and progress."""
from __future__ import annotations

import math

import numpy as np
import pytest

from sumo_avoid.studies.cuckoo import (
    CuckooSearch,
    levy_steps,
    n_abandoned,
    reflect,
    sigma_u,
    tail_constant,
)


def test_sigma_u_by_hand():
    # beta = 1.5: Gamma(2.5) = 1.3293404, sin(0.75 pi) = 0.7071068, Gamma(1.25) = 0.9064025,
    # 2^0.25 = 1.1892071: (0.9399856 / (0.9064025 * 1.5 * 1.1892071))^(1/1.5) = 0.5813624^0.6667 = 0.69657
    assert sigma_u(1.5) == pytest.approx(0.69657, abs=5e-6)
    # beta = 1: Gamma(2) sin(pi/2) / (Gamma(1) * 1 * 2^0) = 1
    assert sigma_u(1.0) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        sigma_u(2.5)


def test_tail_constant_by_hand():
    # beta = 1.5: E|u|^1.5 = 0.5813624 * 2^0.75 * Gamma(1.25) / sqrt(pi) = 0.5000 ; C = sqrt(2/pi) * 0.5
    assert tail_constant(1.5) == pytest.approx(math.sqrt(2 / math.pi) * 0.5, rel=1e-5)
    # beta = 1 (Cauchy-like): E|u| = sqrt(2/pi) ; C = 2/pi
    assert tail_constant(1.0) == pytest.approx(2 / math.pi)


@pytest.mark.parametrize("beta", [1.5, 1.0])
def test_step_tail_follows_power_law(beta):
    # P(|step| > x) = C x^-beta for large x; 2e6 samples, 4 binomial standard deviations
    n = 2_000_000
    s = np.abs(levy_steps(np.random.default_rng(7), beta, n))
    for x in (10.0, 100.0):
        p = tail_constant(beta) * x ** -beta
        assert abs((s > x).mean() - p) < 4 * math.sqrt(p / n), (beta, x)
    # the bulk is not Gaussian: |step| > 10 sigma_u would be ~1e-23 for a normal
    assert (s > 10 * sigma_u(beta)).mean() > 1e-3


def test_abandonment_counts():
    assert [n_abandoned(n, 0.25) for n in (2, 4, 10, 15, 20)] == [1, 1, 3, 4, 5]  # 0.5 -> 1, 2.5 -> 3, 3.75 -> 4
    assert n_abandoned(10, 0.0) == 0
    cs = CuckooSearch(15, 2, np.random.default_rng(0), pa=0.25)
    cs.tell_initial(np.arange(15.0))
    assert sorted(cs.worst().tolist()) == [11, 12, 13, 14]
    new = cs.abandon()
    assert new.shape == (4, 2)
    cs.tell_abandoned(new, np.full(4, -1.0))
    assert sorted(np.flatnonzero(cs.scores == -1.0).tolist()) == [11, 12, 13, 14]
    assert cs.evaluations == 19


def test_reflect():
    assert reflect(np.array([-0.2, 0.3, 1.25, 2.1])) == pytest.approx([0.2, 0.3, 0.75, 0.1])


def _search(seed, gens=30):
    f = lambda u: ((u - np.array([0.3, 0.7])) ** 2).sum(axis=1)
    cs = CuckooSearch(10, 2, np.random.default_rng(seed))
    cs.tell_initial(f(cs.initial()))
    first = cs.best[1]
    for _ in range(gens):
        eggs = cs.propose()
        cs.tell(eggs, f(eggs))
        new = cs.abandon()
        cs.tell_abandoned(new, f(new))
    return cs, first


def test_search_is_deterministic_and_converges():
    a, first = _search(3)
    b, _ = _search(3)
    assert np.array_equal(a.nests, b.nests) and np.array_equal(a.scores, b.scores)
    best, score = a.best
    assert score < first and score < 1e-3
    assert best == pytest.approx([0.3, 0.7], abs=0.03)
    assert ((a.nests >= 0) & (a.nests <= 1)).all()
