"""Cuckoo search with Lévy flights (Yang & Deb 2009; SPEC §3, seed 003), as a small ask/tell
optimiser over the unit cube [0, 1]^D (the caller maps it to its parameters). Pure numpy.

Lévy steps by Mantegna's method: step = u / |v|^(1/beta), u ~ N(0, sigma_u^2), v ~ N(0, sigma_v^2)
with sigma_v = 1 and

    sigma_u = [ Gamma(1 + beta) sin(pi beta / 2) / ( Gamma((1 + beta)/2) beta 2^((beta - 1)/2) ) ]^(1/beta)

(0.69657 at beta = 1.5). For large x, P(|step| > x) -> C x^(-beta) with
C = sqrt(2/pi) E|u|^beta = sqrt(2/pi) sigma_u^beta 2^(beta/2) Gamma((1+beta)/2) / sqrt(pi) (the
small-|v| end; 0.39894 at beta = 1.5): :func:`tail_constant`, checked by the tests on samples.

One generation (:meth:`CuckooSearch.propose` / :meth:`tell`, then :meth:`abandon` /
:meth:`tell_abandoned`):

1. every nest i lays a cuckoo egg: a Lévy flight from the best nest,
   x_new = x_best + step_size * L (L a D-vector of Mantegna steps), reflected back into [0, 1];
2. each egg is compared with a nest j drawn at random and replaces it if its score is lower (Yang);
3. the round(p_a N) worst nests are abandoned and rebuilt at uniform random points (always taken).

The random stream is the caller's numpy Generator: the same seed gives the same candidates, so a
tuner that re-evaluates from a ledger reproduces its run exactly.
"""
from __future__ import annotations

import math

import numpy as np


def sigma_u(beta: float) -> float:
    """Mantegna's sigma_u for the tail index beta in (0, 2]."""
    if not 0.0 < beta <= 2.0:
        raise ValueError("beta must be in (0, 2]")
    num = math.gamma(1.0 + beta) * math.sin(math.pi * beta / 2.0)
    den = math.gamma((1.0 + beta) / 2.0) * beta * 2.0 ** ((beta - 1.0) / 2.0)
    return (num / den) ** (1.0 / beta)


def tail_constant(beta: float) -> float:
    """C of the step's tail P(|step| > x) ~ C x^(-beta) (module doc)."""
    e_u = sigma_u(beta) ** beta * 2.0 ** (beta / 2.0) * math.gamma((1.0 + beta) / 2.0) / math.sqrt(math.pi)
    return math.sqrt(2.0 / math.pi) * e_u


def levy_steps(rng: np.random.Generator, beta: float, size) -> np.ndarray:
    """Mantegna's Lévy steps, shape ``size``: u / |v|^(1/beta) (sigma_v = 1)."""
    u = rng.normal(0.0, sigma_u(beta), size)
    v = rng.normal(0.0, 1.0, size)
    return u / np.abs(v) ** (1.0 / beta)


def n_abandoned(n_nests: int, pa: float) -> int:
    """Nests abandoned per generation: p_a N rounded half up."""
    return math.floor(pa * n_nests + 0.5)


def reflect(x: np.ndarray) -> np.ndarray:
    """Points folded back into [0, 1] (a step past a wall bounces off it)."""
    y = np.mod(x, 2.0)
    return np.where(y > 1.0, 2.0 - y, y)


class CuckooSearch:
    """Ask/tell cuckoo search minimising a score over [0, 1]^dim."""

    def __init__(self, n_nests: int, dim: int, rng: np.random.Generator, beta: float = 1.5, pa: float = 0.25,
                 step_size: float = 0.05):
        if n_nests < 2 or dim < 1:
            raise ValueError("n_nests >= 2 and dim >= 1")
        if not 0.0 <= pa < 1.0:
            raise ValueError("pa must be in [0, 1)")
        sigma_u(beta)  # validates beta
        self.n, self.dim, self.rng, self.beta, self.pa, self.step = n_nests, dim, rng, beta, pa, step_size
        self.nests = rng.uniform(0.0, 1.0, (n_nests, dim))
        self.scores = np.full(n_nests, np.inf)
        self.evaluations = 0

    def initial(self) -> np.ndarray:
        """The first nests, to be scored with :meth:`tell_initial`."""
        return self.nests.copy()

    def tell_initial(self, scores) -> None:
        self.scores = np.asarray(scores, float).copy()
        self.evaluations += len(self.scores)

    @property
    def best(self) -> tuple[np.ndarray, float]:
        k = int(np.argmin(self.scores))
        return self.nests[k].copy(), float(self.scores[k])

    def propose(self) -> np.ndarray:
        """One egg per nest: a Lévy flight from the best nest, (n, dim)."""
        best, _ = self.best
        return reflect(best + self.step * levy_steps(self.rng, self.beta, (self.n, self.dim)))

    def tell(self, eggs, scores) -> int:
        """Each egg against a random nest (replaced if the egg scores lower). Returns replacements."""
        eggs, scores = np.asarray(eggs, float), np.asarray(scores, float)
        self.evaluations += len(scores)
        replaced = 0
        for egg, s, j in zip(eggs, scores, self.rng.integers(0, self.n, len(eggs))):  # sequential by definition
            if s < self.scores[j]:
                self.nests[j], self.scores[j] = egg, s
                replaced += 1
        return replaced

    def worst(self) -> np.ndarray:
        """Indices of the round(p_a n) worst nests (highest scores; ties by index)."""
        k = n_abandoned(self.n, self.pa)
        return np.argsort(-self.scores, kind="stable")[:k]

    def abandon(self) -> np.ndarray:
        """New random nests for the worst ones, (k, dim), to be scored with :meth:`tell_abandoned`."""
        return self.rng.uniform(0.0, 1.0, (len(self.worst()), self.dim))

    def tell_abandoned(self, nests, scores) -> None:
        idx = self.worst()
        self.nests[idx] = np.asarray(nests, float)
        self.scores[idx] = np.asarray(scores, float)
        self.evaluations += len(idx)
