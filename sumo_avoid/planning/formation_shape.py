"""The shape of a formation (SPEC §3, seed 003), as data both the ``formation`` controller and its
metric (S_ef's distortion, :mod:`sumo_avoid.metrics.formation_score`) use: the slots of a shape in
the **formation frame** (x forward along the leader's heading, y to its left, metres, the leader at
(0, 0)), their place in the world, and which member holds which slot.
"""
from __future__ import annotations

import re

import numpy as np

SHAPES = ("triangle", "line", "column", "v", "diamond")


def slots(shape: str, n: int, spacing_m: float, apex_deg: float = 90.0) -> np.ndarray:
    """(n, 2) slots (x forward, y left, m) of ``n`` vehicles, slot 0 = the leader at (0, 0).

    * ``triangle``: row k (k = 1, 2, ...) ``k * spacing`` behind the leader holds k + 1 vehicles
      spread evenly from ``-k s tan(A/2)`` to ``+k s tan(A/2)`` (A = apex angle): with A = 90
      deg and n = 6 exactly the seed's (0,0), (-1,-1), (-1,1), (-2,-2), (-2,2), (-2,0) times s;
      a row is filled right (y < 0), left, then inwards, as the seed lists them;
    * ``v``: the triangle's two edges only: follower j on row ceil(j/2), right then left;
    * ``line`` (line abreast): everyone on the leader's row, right, left, right, ... ``spacing`` apart;
    * ``column``: one behind the other, ``spacing`` apart;
    * ``diamond``: leader, (-s, -+s tan(A/2)), (-2 s, 0) (A = 90 deg: (-1, -+1), (-2, 0) times s), then
      the same diamond again 2 s further back (its apex at -2 s shared, so -3 s: +-1, -4 s: 0), and so on.
    """
    if shape not in SHAPES:
        raise ValueError(f"shape must be one of {list(SHAPES)}")
    s, t = float(spacing_m), float(np.tan(np.radians(apex_deg) / 2.0))
    out = [(0.0, 0.0)]
    if shape == "triangle":
        k = 1
        while len(out) < n:
            ys = np.linspace(-k * t, k * t, k + 1)  # right to left
            order = [0, k] + [i for pair in zip(range(1, k), range(k - 1, 0, -1)) for i in pair]
            seen = []
            for i in order:  # right, left, then inwards (the seed's order: (-2,-2), (-2,2), (-2,0))
                if i not in seen:
                    seen.append(i)
            out += [(-k * s, ys[i] * s) for i in seen]
            k += 1
    elif shape == "v":
        out += [(-((j + 1) // 2) * s, (-1 if j % 2 else 1) * ((j + 1) // 2) * t * s) for j in range(1, n)]
    elif shape == "line":
        out += [(0.0, (-1 if j % 2 else 1) * ((j + 1) // 2) * s) for j in range(1, n)]
    elif shape == "column":
        out += [(-j * s, 0.0) for j in range(1, n)]
    else:  # diamond
        j = 1
        while len(out) < n:
            base = -2.0 * ((j - 1) // 3) * s
            out.append([(base - s, -s * t), (base - s, s * t), (base - 2 * s, 0.0)][(j - 1) % 3])
            j += 1
    return np.asarray(out[:n], float)


def to_world(offsets: np.ndarray, origin: np.ndarray, heading: float, lateral_scale: float = 1.0) -> np.ndarray:
    """Slots (n, 2) of the formation frame, y scaled by ``lateral_scale``, placed at the leader's
    ``origin`` (2,) turned by ``heading`` (rad CCW from +x): (n, 2) world points, m."""
    c, s = np.cos(heading), np.sin(heading)
    x, y = offsets[:, 0], offsets[:, 1] * lateral_scale
    return np.asarray(origin, float) + np.column_stack([c * x - s * y, s * x + c * y])


def natural_key(vid: str):
    """Sort key: digits as numbers (f2 before f10)."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", vid)]


def member_order(params, ego_ids) -> list[str]:
    """Slot order of the formation: ``params.members`` (``[controllers.formation]``) if given, else
    the ids in natural order."""
    return list(params.members) if params.members else sorted(ego_ids, key=natural_key)
