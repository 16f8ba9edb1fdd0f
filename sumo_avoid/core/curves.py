"""The braking curve of the flocking model (SPEC §1 eq. 3): shared by the controller and the metrics."""
from __future__ import annotations

import numpy as np


def _ret(x):
    x = np.asarray(x, float)
    return float(x) if x.ndim == 0 else x


def braking_curve_D(r, a, p):
    """Braking curve D(r, a, p), m/s (SPEC §1, seed eq. 3); vectorised over broadcast inputs.

    r: distance to the stopping point, m; a: acceleration, m/s² (> 0); p: linear gain, 1/s (> 0).
        D = 0                        r <= 0
          = r p                      0 < r p < a / p
          = sqrt(2 a r - a²/p²)      otherwise (continuous with r p at r p = a/p)
    """
    r, a, p = np.broadcast_arrays(*(np.asarray(v, float) for v in (r, a, p)))
    with np.errstate(divide="ignore", invalid="ignore"):
        lin = r * p
        sq = np.sqrt(np.maximum(2.0 * a * r - (a / p) ** 2, 0.0))
        out = np.where(r <= 0, 0.0, np.where(lin < a / p, lin, sq))
    return _ret(out)
