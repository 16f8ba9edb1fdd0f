"""Levels: bridges and tunnels. SUMO gives every lane a shape with z and every road user a z (the
z of its position on its lane, ``vehicle.getPosition3D`` / ``person.getPosition3D``); the snapshot
carries it (:attr:`~sumo_avoid.core.snapshot.Snapshot.z`), and so does the recording (column ``z``,
written when a run has any z other than 0).

Two road users are on the *same level* when their z differ by at most
:attr:`Levels.clearance_m`; otherwise one passes over the other (a bridge, a tunnel) and neither is an
obstacle for the other (the sensors -- ground truth and radar: a radar does not see through a
bridge deck -- and the controllers), nor a collision, a gap or a TTC pair for the metrics.
On a flat net (every z 0) everyone is on one level and nothing changes. Heights are not all: two road users on
edges whose lanes cross without a junction are on two levels whatever their z (:mod:`sumo_avoid.road.grade`, whose
table of such edges ``apart`` the functions below take: ``part_of``, ``apart_mask``, ``apart_pairs``).

The threshold: a road bridge leaves a vertical clearance of at least about 4.5 m under it (4.5 m to
5.1 m in most European and US standards), plus its deck, so road users on two levels are at least
~5.5 m apart in z; on one road, two road users close enough to matter are never 4 m apart in z (a
steep 10 % ramp rises 1 m over 10 m). 4 m lies between.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Levels:
    clearance_m: float = 4.0  # |z_a - z_b| above this: on two levels (a bridge over a road), m


LEVELS = Levels()


def same_level(z_a, z_b, levels: Levels = LEVELS) -> np.ndarray:
    """Elementwise: whether road users at heights ``z_a`` and ``z_b`` (m) share a level."""
    return np.abs(np.asarray(z_a, float) - np.asarray(z_b, float)) <= levels.clearance_m


def has_levels(z, levels: Levels = LEVELS) -> bool:
    """Whether heights ``z`` (m) span more than one level (else every level test is true)."""
    z = np.asarray(z, float)
    return bool(z.size) and float(np.ptp(z)) > levels.clearance_m


def part_of(lane_id: str) -> str:
    """The part of the net a SUMO lane id lies on: its edge (``E`` for ``E_0``), or for a junction's internal lane,
    crossing or walking area (``:J_3_0``, ``:J_c0_0``, ``:J_w1_0``) the junction, as ``:J``; "" for none."""
    if not lane_id:
        return ""
    edge = lane_id.rsplit("_", 1)[0]
    return ":" + edge[1:].rsplit("_", 1)[0] if edge.startswith(":") else edge


def apart_mask(apart: Mapping[str, frozenset[str]], lane: str, lanes) -> np.ndarray:
    """(len(lanes),) bool: which of ``lanes`` (SUMO lane ids) lie on a part of the net apart from ``lane``'s."""
    far = apart.get(part_of(lane), frozenset()) if apart else frozenset()
    return np.array([bool(far) and part_of(x) in far for x in lanes], bool)


def apart_pairs(apart: Mapping[str, frozenset[str]], lanes_a, lanes_b) -> np.ndarray:
    """(K,) bool for K pairs of SUMO lane ids ``lanes_a[k]``, ``lanes_b[k]``: whether the two lie on parts of the net
    apart from each other (vectorised over the pairs: a run's table has millions)."""
    a, b = np.asarray(lanes_a, dtype=object), np.asarray(lanes_b, dtype=object)
    if not apart or not len(a):
        return np.zeros(len(a), bool)
    lanes, inv = np.unique(np.concatenate([a, b]).astype(str), return_inverse=True)
    part = [part_of(x) for x in lanes]
    code = {p: k for k, p in enumerate(dict.fromkeys(part))}
    c = np.array([code[p] for p in part], np.int64)[inv.ravel()]
    n = len(code)
    keys = np.array([code[p] * n + code[q] for p in code for q in apart.get(p, ()) if q in code], np.int64)
    return np.isin(c[:len(a)] * n + c[len(a):], keys)
