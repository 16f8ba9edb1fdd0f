"""The pure maths of the ``formation`` controller (SPEC §3, seed 003): the goal-aware potential
field with its alpha/beta reshaping, the width ratio gamma with the mode kappa, and the shape's
lateral scale. The shapes themselves (slots in the formation frame: x forward along the leader's
heading, y to its left, metres, the leader at (0, 0)) are :mod:`sumo_avoid.planning.formation_shape`.
Nothing here knows SUMO or time.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull

from sumo_avoid.core.geometry import convex_distance, pad_polygons


# ------------------------------------------------------------------------------------- shape scale
def min_lateral_scale(offsets: np.ndarray, length_m: float, width_m: float, gap_m: float) -> float:
    """The smallest lateral scale s_min at which the shape's vehicles keep ``gap_m`` sideways:
    over every pair of slots closer than ``length_m + gap_m`` along x (they would overlap
    lengthwise), s_min = (width + gap) / |dy|; 0 when no pair overlaps lengthwise. At most 1."""
    dx = np.abs(offsets[:, None, 0] - offsets[None, :, 0])
    dy = np.abs(offsets[:, None, 1] - offsets[None, :, 1])
    side = (dx < length_m + gap_m) & ~np.eye(len(offsets), dtype=bool)
    if not side.any():
        return 0.0
    return float(min(1.0, ((width_m + gap_m) / np.maximum(dy[side], 1e-9)).max()))


# --------------------------------------------------------------------- the goal-aware field (SPEC §3)
def attraction(q, goal, eta_at: float) -> np.ndarray:
    """F_at = eta_at * rho_g towards the goal, at points q (E, 2): (E, 2)."""
    return eta_at * (np.asarray(goal, float) - np.asarray(q, float))


def repulsion_terms(rho, away, rho_g, to_goal, eta_re: float, rho0: float, n: float):
    """The goal-aware repulsion of M obstacle distances (SPEC §3, Ge & Cui).

    rho (M,) obstacle distances, m (floored by the caller); away (M, 2) unit vectors from the
    obstacle towards the vehicle; rho_g (M,) the vehicle's distance to its goal, m; to_goal (M, 2)
    unit vectors towards the goal. Zero where rho > rho0. Returns (F_re1 (M, 2), F_re2 (M, 2)):

        F_re1 = eta_re (1/rho - 1/rho0) rho_g^n / rho^2          along ``away``
        F_re2 = (n/2) eta_re (1/rho - 1/rho0)^2 rho_g^(n-1)      along ``to_goal``
    """
    rho = np.asarray(rho, float)
    k = np.where(rho <= rho0, 1.0 / rho - 1.0 / rho0, 0.0)
    rg = np.asarray(rho_g, float)
    f1 = eta_re * k * rg**n / rho**2
    f2 = 0.5 * n * eta_re * k**2 * np.where(rg > 0, rg, 1.0) ** (n - 1.0) * (rg > 0)
    return f1[:, None] * away, f2[:, None] * to_goal


def reshape(f_re: np.ndarray, heading, alpha: float, beta: float) -> np.ndarray:
    """SPEC §3 local-minimum fix in the vehicle frame (p along the heading, q to its left):
    F_p' = (1 + alpha) F_p, F_q' = F_q + beta |F_re|. f_re (E, 2) world, heading (E,) rad."""
    f_re = np.atleast_2d(np.asarray(f_re, float))
    h = np.broadcast_to(np.asarray(heading, float), (len(f_re),))
    c, s = np.cos(h), np.sin(h)
    p = c * f_re[:, 0] + s * f_re[:, 1]
    q = -s * f_re[:, 0] + c * f_re[:, 1]
    p2, q2 = (1.0 + alpha) * p, q + beta * np.hypot(f_re[:, 0], f_re[:, 1])
    return np.column_stack([c * p2 - s * q2, s * p2 + c * q2])


def bridges(polys: np.ndarray, passage_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Gaps the members cannot pass, closed for the field: for every pair of convex polygons (O, K, 2)
    less than ``passage_m`` apart, the convex hull of the two. The safety shield keeps a member's
    disc (its half diagonal r) ``margin`` from every obstacle, so a gap narrower than 2 (r + margin)
    is shut to it; the field, which measures from the footprint, would still lead a member into it,
    where the shield holds it for good. Returns (hulls (B, H, 2) CCW, padded,
    pairs (B, 2) the indices i < j they join)."""
    polys = np.asarray(polys, float)
    if len(polys) < 2:
        return np.zeros((0, 3, 2)), np.zeros((0, 2), int)
    i, j = np.triu_indices(len(polys), 1)
    d, _, _ = convex_distance(polys[i], polys[j])
    close = d < passage_m
    if not close.any():
        return np.zeros((0, 3, 2)), np.zeros((0, 2), int)
    hulls = []
    for a, b in zip(i[close], j[close]):
        pts = np.vstack([polys[a], polys[b]])
        hulls.append(pts[ConvexHull(pts).vertices])  # counter-clockwise
    return pad_polygons(hulls), np.column_stack([i[close], j[close]])


# --------------------------------------------------------------------------- width ratio and mode
def formation_width(lateral: np.ndarray, width_m: float) -> float:
    """W: the formation's width across the leader's heading, from the members' lateral offsets
    (m, in the formation frame): max - min + one vehicle width."""
    return float(np.ptp(lateral) + width_m) if len(lateral) else float(width_m)


def free_width(intervals: np.ndarray, half_window_m: float) -> float:
    """W_max: the free width across the leader's heading, from the lateral intervals [lo, hi] (m,
    formation frame, (K, 2)) that obstacles ahead occupy, within [-half_window, +half_window].

    The free gaps are the complement of the intervals within the window. If the leader's line
    (y = 0) lies in a gap [lo, hi], W_max = 2 min(-lo, hi): the width free *centred on the leader*,
    since the shape is held about the leader; if an obstacle covers y = 0 the leader's field takes
    it round one side, and W_max is the width of the wider of the two gaps next to the obstacles
    covering it. With nothing ahead W_max = 2 half_window."""
    return free_gap(intervals, half_window_m)[2]


def free_gap(intervals: np.ndarray, half_window_m: float) -> tuple[float, float, float]:
    """(lo, hi, W_max) of :func:`free_width`: the free gap it measures (the one about the leader's
    line, or the wider one next to the obstacles covering it), m; its centre is where the leader
    would have to be for the whole gap to count."""
    lo_w, hi_w = -float(half_window_m), float(half_window_m)
    iv = np.asarray(intervals, float).reshape(-1, 2)
    iv = iv[(iv[:, 1] > lo_w) & (iv[:, 0] < hi_w)]
    if len(iv) == 0:
        return lo_w, hi_w, hi_w - lo_w
    iv = np.clip(iv[np.argsort(iv[:, 0])], lo_w, hi_w)
    merged = [list(iv[0])]
    for a, b in iv[1:]:  # merge overlapping intervals (a few per step)
        if a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    edges = np.array([lo_w] + [x for ab in merged for x in ab] + [hi_w]).reshape(-1, 2)  # gaps [lo, hi]
    widths = np.maximum(edges[:, 1] - edges[:, 0], 0.0)
    inside = np.flatnonzero((edges[:, 0] <= 0.0) & (edges[:, 1] >= 0.0))
    if len(inside):
        lo, hi = edges[inside[0]]
        return float(lo), float(hi), float(2.0 * min(-lo, hi))
    blocked = next(i for i, (a, b) in enumerate(merged) if a <= 0.0 <= b)  # merged block i: gaps i, i + 1
    k = blocked if widths[blocked] >= widths[blocked + 1] else blocked + 1
    return float(edges[k, 0]), float(edges[k, 1]), float(widths[k])


def gamma_min(s_min: float, span_m: float, width_m: float, clear_m: float, W: float) -> float:
    """The gamma at which the lateral scale needed to fit reaches ``s_min`` (SPEC §3 gamma_min):
    gamma_min = (s_min span + width + 2 clear) / W."""
    return float((s_min * span_m + width_m + 2.0 * clear_m) / W)


def lateral_scale(W_max: float, span_m: float, width_m: float, clear_m: float) -> float:
    """Lateral scale s that makes the formation (span ``span_m`` between outer centres) fit a free
    width W_max with ``clear_m`` on each side: (W_max - 2 clear - width) / span, within [0, 1]."""
    if span_m <= 0:
        return 1.0
    return float(np.clip((W_max - 2.0 * clear_m - width_m) / span_m, 0.0, 1.0))


def mode(gamma: float, g_min: float) -> int:
    """kappa (SPEC §3): 1 keep (gamma >= 1), 2 scale laterally (g_min < gamma < 1), 3 break up."""
    if gamma >= 1.0:
        return 1
    return 2 if gamma > g_min else 3
