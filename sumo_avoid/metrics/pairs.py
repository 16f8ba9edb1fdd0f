"""Vehicle pairs of one recorded step closer than a radius, for the pair metrics of
:mod:`sumo_avoid.metrics.basic` (collision events, smallest gap, φ_coll).

The pairs are those the metrics define (SPEC eq. 12 and README "Metrics"): at one step, an ego
``i`` and any other vehicle ``j`` present, each unordered pair once. They are found with one
scipy ``cKDTree`` over the whole run instead of listing every pair of every step: each row is the
2-d point (x - min x + step index × gap, y), the gap larger than the x range plus any distance
inside a step, so a radius search never joins two steps (a 2-d tree answers about five times
faster here than one with the step as a third coordinate). The shift rounds the x coordinates
(by at most half a unit in the last place of the largest shifted x, :attr:`Rows.round_m` bounds
the error of a distance): the search radius is widened by that and slightly more.
The search radius is widened slightly (:data:`WIDEN`, :data:`SLACK_M`) and is at least
:attr:`Rows.min_search_m` (the largest footprint diagonal + 1 m, enough for the collision test, the
first round of the smallest gap and φ_coll's 3 m), and the widest search so far is kept and
reused for smaller radii: the pairs returned are a superset of those within the radius, one search
serves the three metrics when they share a :class:`Rows`, and each metric then applies its own
exact test to the distances it computes itself (``np.hypot`` of the coordinate
differences), so the results do not depend on the tree's rounding or on which pairs beyond the radius
came along.

Pairs are of road users on one level (:mod:`sumo_avoid.core.levels`, with the table's ``z`` column): a
car on a bridge over the ego is no pair of its.

Orientation, as in an enumeration over rows sorted by (step, id): ``i`` is the ego of an
ego/non-ego pair, and of two egos the one that comes first in that order (the smaller id).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from sumo_avoid.core.levels import apart_pairs, has_levels, same_level

WIDEN = 1.0 + 1e-9  # relative widening of a search radius
SLACK_M = 1e-9  # absolute widening, m


@dataclass
class Rows:
    """The columns of a trajectory table the pair metrics use, in the table's row order."""

    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    length: np.ndarray
    width: np.ndarray
    time_s: np.ndarray
    step: np.ndarray  # int64
    ids: np.ndarray  # str (object), the ``id`` column
    is_ego: np.ndarray  # bool
    z: np.ndarray | None = None  # height, m (the ``z`` column; None: a flat net, all 0)
    lane: np.ndarray | None = None  # SUMO lane id (the ``lane`` column; with ``apart``: pairs on crossing edges drop out)
    apart: dict | None = None  # edges crossing without a junction (road.grade: two levels whatever the heights)
    uniq: np.ndarray = field(init=False)  # distinct steps, ascending
    rank: np.ndarray = field(init=False)  # index of each row's step in uniq
    order_pos: np.ndarray = field(init=False)  # position of each row when sorted by (step, id), stable
    extent_m: float = field(init=False)  # > any centre distance inside a step
    min_search_m: float = field(init=False)  # smallest search radius: largest diagonal + 1 m
    gap_m: float = field(init=False)  # x shift per step index
    round_m: float = field(init=False)  # bound on a distance's error from the shift, m
    _trees: dict = field(init=False, default_factory=dict, repr=False)

    def __post_init__(self):
        self.uniq, self.rank = np.unique(self.step, return_inverse=True)
        self.rank = self.rank.ravel()
        code = pd.factorize(self.ids, sort=True)[0]  # codes in the order of the ids
        o = np.lexsort((code, self.step))  # = sort_values(["step", "id"], kind="stable")
        self.order_pos = np.empty(len(o), np.int64)
        self.order_pos[o] = np.arange(len(o))
        n = len(self.x)
        span = float(np.ptp(self.x) + np.ptp(self.y)) if n else 0.0
        self.extent_m = span * WIDEN + 1.0
        self.min_search_m = float(np.hypot(self.length.max(), self.width.max())) + 1.0 if n else 0.0
        self.gap_m = float(np.ptp(self.x)) + 2.0 * self.extent_m + 1.0 if n else 1.0
        top = self.gap_m * (float(self.rank.max()) + 1.0) if n else 0.0  # > any shifted x
        self.round_m = 4.0 * float(np.spacing(top))  # each shifted x is off by <= spacing/2
        self._found = (-np.inf, None, None)  # widest search so far: radius, i, j

    @classmethod
    def of(cls, traj: pd.DataFrame, apart=None) -> "Rows":
        """The table's rows; with ``apart`` (``Road.apart``) and a ``lane`` column, pairs on edges crossing without a
        junction are on two levels."""
        col = {c: traj[c].to_numpy(dtype=float) for c in ("x", "y", "heading", "length", "width", "time_s")}
        lane = traj["lane"].fillna("").astype(str).to_numpy(dtype=object) if apart and "lane" in traj else None
        return cls(**col, step=traj["step"].to_numpy(dtype=np.int64),
                   ids=traj["id"].astype(str).to_numpy(dtype=object), is_ego=traj["is_ego"].to_numpy(dtype=bool),
                   z=traj["z"].to_numpy(dtype=float) if "z" in traj else None, lane=lane, apart=apart or None)

    def _tree(self, egos: bool):
        """cKDTree of the ego (or non-ego) rows in the stacked coordinates, and those rows."""
        if egos not in self._trees:
            rows = np.flatnonzero(self.is_ego == egos)
            pts = np.column_stack([(self.x[rows] - self.x.min()) + self.rank[rows] * self.gap_m, self.y[rows]])
            self._trees[egos] = (cKDTree(pts, balanced_tree=False, compact_nodes=False) if len(rows) else None, rows)
        return self._trees[egos]

    def pairs_within(self, radius_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Row index arrays (i, j) of every pair of one step with centre distance <= radius_m
        (and possibly farther ones; see the module doc), i an ego, oriented as above."""
        r = min(max(float(radius_m), self.min_search_m), self.extent_m)  # beyond extent_m: all in-step pairs
        if r <= self._found[0]:
            return self._found[1], self._found[2]
        i, j = self._search(r * WIDEN + SLACK_M + self.round_m)
        self._found = (r, i, j)
        return i, j

    def _search(self, r: float) -> tuple[np.ndarray, np.ndarray]:
        t_ego, ego = self._tree(True)
        if t_ego is None or not r >= 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        pr = t_ego.query_pairs(r, output_type="ndarray")
        a, b = ego[pr[:, 0]], ego[pr[:, 1]]
        swap = self.order_pos[b] < self.order_pos[a]
        i, j = [np.where(swap, b, a)], [np.where(swap, a, b)]
        t_other, other = self._tree(False)
        if t_other is not None:
            m = t_ego.sparse_distance_matrix(t_other, r, output_type="ndarray")
            i.append(ego[m["i"]])
            j.append(other[m["j"]])
        i, j = np.concatenate(i).astype(np.int64), np.concatenate(j).astype(np.int64)
        if self.z is not None and has_levels(self.z):  # only pairs on one level (core.levels)
            keep = same_level(self.z[i], self.z[j])
            i, j = i[keep], j[keep]
        if self.lane is not None and self.apart:  # ... also by the net's topology (road.grade)
            keep = ~apart_pairs(self.apart, self.lane[i], self.lane[j])
            i, j = i[keep], j[keep]
        return i, j
