"""The potential field's two terms (SPEC §2, seed 001 eq. 3-8 and 13-14): pure numpy, no road."""
from __future__ import annotations

import numpy as np


def attraction(q, target, k_att, d):
    """SPEC §2 capped attraction at points q (C,2): returns U (C,), F (C,2)."""
    diff = np.asarray(q, float) - np.asarray(target, float)
    rho = np.hypot(diff[:, 0], diff[:, 1])
    near = rho <= d
    U = np.where(near, 0.5 * k_att * rho**2, d * k_att * rho - 0.5 * k_att * d**2)
    scale = np.where(near, k_att, d * k_att / np.maximum(rho, 1e-12))
    return U, -scale[:, None] * diff


def repulsion(rho, direction, rho0, k_rep, rho_floor=0.2):
    """SPEC §2 repulsion for M obstacle distances rho (M,), unit directions (M,2) away from the
    obstacle, influence distances rho0 (M,): returns U (M,), F (M,2)."""
    r = np.maximum(np.asarray(rho, float), rho_floor)
    inside = r < rho0
    diff = np.where(inside, 1.0 / r - 1.0 / rho0, 0.0)
    U = 0.5 * k_rep * diff**2
    F = (k_rep * diff / r**2)[:, None] * direction
    return U, F


def unit_and_norm(v):
    """(..., 2) unit vectors and their norms (a zero vector stays zero)."""
    n = np.hypot(v[..., 0], v[..., 1])
    return v / np.maximum(n, 1e-12)[..., None], n
