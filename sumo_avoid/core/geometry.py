"""Pure-numpy 2-D geometry for vehicle footprints (no SUMO, no shapely; scipy only in near_any's fallback).

Conventions (SPEC preamble): lengths in metres, SUMO network coordinates (x east, y north),
headings in radians counter-clockwise from +x, positions are vehicle *centres*.

Polygons are ``(..., k, 2)`` arrays of vertices in counter-clockwise (CCW) order, implicitly
closed (edge ``k-1 -> 0``). A 2-vertex "polygon" is a segment and a 1-vertex one is a point; every
function here accepts those degenerate shapes. Batched functions take ``M`` pairs of polygons,
all P of one size ``k`` and all Q of one size ``m``, and never loop over pairs in Python.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

#: Contact tolerance, m. Two shapes whose separation is at most this count as touching/overlapping.
CONTACT_TOL_M = 1e-9

__all__ = [
    "CONTACT_TOL_M",
    "footprint_corners",
    "convex_overlap",
    "convex_distance",
    "point_segment_distance",
    "pairwise_footprint_distance",
    "ccw_polygon",
    "pad_polygons",
    "ring_walls",
    "near_any",
    "box_gap",
]


def footprint_corners(pos, heading, length, width) -> np.ndarray:
    """Corners of oriented rectangles (vehicle footprints).

    Parameters
    ----------
    pos : (N, 2) centre positions, m.
    heading : (N,) rad, CCW from +x (the direction the vehicle's front points).
    length, width : (N,) or scalar, m (length along the heading, width across it).

    Returns
    -------
    (N, 4, 2) corners, m, in CCW order: **front-right, front-left, rear-left, rear-right**.
    (For heading 0 that is (+L/2, -W/2), (+L/2, +W/2), (-L/2, +W/2), (-L/2, -W/2) about the centre.)
    """
    pos = np.asarray(pos, float).reshape(-1, 2)
    n = pos.shape[0]
    h = np.broadcast_to(np.asarray(heading, float), (n,))
    hl = 0.5 * np.broadcast_to(np.asarray(length, float), (n,))  # half length, m
    hw = 0.5 * np.broadcast_to(np.asarray(width, float), (n,))  # half width, m
    fwd = np.stack([np.cos(h), np.sin(h)], axis=-1)  # (N,2) unit vector along the heading
    left = np.stack([-fwd[:, 1], fwd[:, 0]], axis=-1)  # (N,2) unit vector 90 deg CCW of heading
    sl = np.array([1.0, 1.0, -1.0, -1.0])  # +front / -rear
    sw = np.array([-1.0, 1.0, 1.0, -1.0])  # -right / +left
    return (pos[:, None, :]
            + (sl[None, :, None] * hl[:, None, None]) * fwd[:, None, :]
            + (sw[None, :, None] * hw[:, None, None]) * left[:, None, :])


# ---------------------------------------------------------------------------------------------
# point / segment helpers
# ---------------------------------------------------------------------------------------------
def _closest_on_segments(p, a, b):
    """Closest point on segment [a, b] to p, all broadcast together (..., 2). Returns (dist, pt).

    Zero-length segments (a == b) are points: the closest point is a.
    """
    ab = b - a
    ap = p - a
    den = np.einsum("...i,...i->...", ab, ab)  # |ab|^2, m^2
    num = np.einsum("...i,...i->...", ap, ab)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(den > 0.0, num / np.where(den > 0.0, den, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    c = a + t[..., None] * ab
    d = np.hypot(p[..., 0] - c[..., 0], p[..., 1] - c[..., 1])
    return d, c


def point_segment_distance(p, a, b):
    """Distance from M points to K segments.

    Parameters
    ----------
    p : (M, 2) points, m.  a, b : (K, 2) segment end points, m (a == b allowed: a point).

    Returns
    -------
    dist : (M, K) Euclidean distances, m.
    closest : (M, K, 2) closest point on each segment, m (an end point when the foot of the
        perpendicular falls outside the segment; ``a`` for a zero-length segment).
    """
    p = np.asarray(p, float).reshape(-1, 2)
    a = np.asarray(a, float).reshape(-1, 2)
    b = np.asarray(b, float).reshape(-1, 2)
    return _closest_on_segments(p[:, None, :], a[None, :, :], b[None, :, :])


def wrap_angle(a):
    """Wrap radians to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def _edges(P):
    """Edge start and end points of closed polygons P (M,k,2) -> (M,k,2), (M,k,2)."""
    return P, np.roll(P, -1, axis=-2)


def unit_norm(v, eps: float = 1e-12):
    """(unit vectors, lengths) of (..., 2) vectors; a vector no longer than ``eps`` gives 0."""
    n = np.hypot(v[..., 0], v[..., 1])
    return np.where((n > eps)[..., None], v / np.maximum(n, eps)[..., None], 0.0), n


def _unit(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 0.0, v / np.where(n > 0.0, n, 1.0), 0.0)


# ---------------------------------------------------------------------------------------------
# overlap (separating-axis test)
# ---------------------------------------------------------------------------------------------
def _max_separation(P, Q):
    """Largest gap, m, between the projections of P and Q over a set of candidate axes (M,).

    Axes: the unit normals and unit directions of every edge of P and of Q, plus the unit vector
    between the vertex means. The edge normals alone are the classic 2-D SAT axes for convex
    polygons; the edge directions and the centre line make the test exact for degenerate shapes
    too (collinear segments, point vs point). A gap > 0 on any axis proves separation; for convex
    shapes that intersect no axis has a gap > 0.
    """
    ea = np.roll(P, -1, axis=-2) - P  # (M,k,2) edge vectors of P
    eb = np.roll(Q, -1, axis=-2) - Q
    cdir = Q.mean(axis=-2) - P.mean(axis=-2)  # (M,2)
    axes = np.concatenate([
        ea, eb,
        np.stack([ea[..., 1], -ea[..., 0]], axis=-1),  # outward normals for CCW order
        np.stack([eb[..., 1], -eb[..., 0]], axis=-1),
        cdir[:, None, :],
    ], axis=-2)
    axes = _unit(axes)  # zero axes project everything to 0 -> gap 0, never a false separation
    pp = np.einsum("mkd,mad->mka", P, axes)  # (M,k,A) projections, m
    qq = np.einsum("mkd,mad->mka", Q, axes)
    gap = np.maximum(qq.min(axis=1) - pp.max(axis=1), pp.min(axis=1) - qq.max(axis=1))  # (M,A)
    return gap.max(axis=-1)


def _as_pairs(P, Q):
    P = np.asarray(P, float)
    Q = np.asarray(Q, float)
    if P.ndim == 2:
        P = P[None]
    if Q.ndim == 2:
        Q = Q[None]
    m = max(P.shape[0], Q.shape[0])
    return (np.broadcast_to(P, (m,) + P.shape[1:]), np.broadcast_to(Q, (m,) + Q.shape[1:]))


def convex_overlap(P, Q, tol: float = CONTACT_TOL_M) -> np.ndarray:
    """Contact test for M pairs of convex polygons (separating-axis theorem).

    Parameters
    ----------
    P : (M, k, 2), Q : (M, m, 2) vertices, m, CCW order (k, m >= 1; segments and points allowed).
    tol : m. Contact means the shapes share interior area **or touch**: they are reported as
        overlapping unless some axis separates their projections by more than ``tol`` (1e-9 m).
        So shapes exactly touching along an edge or at a corner count as contact.

    Returns
    -------
    (M,) bool.
    """
    P, Q = _as_pairs(P, Q)
    if P.shape[0] == 0:
        return np.zeros(0, bool)
    return _max_separation(P, Q) <= tol


# ---------------------------------------------------------------------------------------------
# distance
# ---------------------------------------------------------------------------------------------
def _inside_convex(pts, Q, tol):
    """Whether points pts (M,n,2) lie inside or on convex CCW polygons Q (M,m,2) -> (M,n) bool.

    Only the interior test for polygons with >= 3 vertices; boundary contact is checked by the
    caller through vertex-edge distances.
    """
    if Q.shape[1] < 3:
        return np.zeros(pts.shape[:2], bool)
    a, b = _edges(Q)
    e = (b - a)[:, None, :, :]  # (M,1,m,2)
    w = pts[:, :, None, :] - a[:, None, :, :]  # (M,n,m,2)
    cross = e[..., 0] * w[..., 1] - e[..., 1] * w[..., 0]  # >= 0 on the left of each CCW edge
    return np.all(cross >= -tol, axis=-1)


def _edge_intersections(P, Q, tol):
    """Proper intersection points of every edge of P with every edge of Q.

    Returns (pts (M,k*m,2), valid (M,k*m) bool). Parallel edges are never reported (their common
    points, if any, are vertices already covered by the vertex-on-boundary test).
    """
    a, b = _edges(P)
    c, d = _edges(Q)
    r = (b - a)[:, :, None, :]  # (M,k,1,2)
    s = (d - c)[:, None, :, :]  # (M,1,m,2)
    qp = c[:, None, :, :] - a[:, :, None, :]  # (M,k,m,2)
    den = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    ok = np.abs(den) > 1e-15
    safe = np.where(ok, den, 1.0)
    t = (qp[..., 0] * s[..., 1] - qp[..., 1] * s[..., 0]) / safe
    u = (qp[..., 0] * r[..., 1] - qp[..., 1] * r[..., 0]) / safe
    eps = 1e-12
    valid = ok & (t >= -eps) & (t <= 1 + eps) & (u >= -eps) & (u <= 1 + eps)
    pts = a[:, :, None, :] + t[..., None] * r
    M = P.shape[0]
    return pts.reshape(M, -1, 2), valid.reshape(M, -1)


def convex_distance(P, Q, tol: float = CONTACT_TOL_M):
    """Euclidean distance between M pairs of convex polygons (segments/points allowed).

    Parameters
    ----------
    P : (M, k, 2), Q : (M, m, 2) vertices, m, CCW order.

    Returns
    -------
    dist : (M,) m. For separated shapes the minimum over all vertex-to-edge distances both ways
        (vertices of P to edges of Q, vertices of Q to edges of P), which is exact for convex
        polygons. Exactly 0 where :func:`convex_overlap` reports contact.
    p_on_P, q_on_Q : (M, 2) m, the closest points realising ``dist``. Where the shapes are in
        contact both are the same common point: a vertex of one shape lying inside/on the other if
        there is one (P's vertices first), otherwise an intersection point of two edges.
    """
    P, Q = _as_pairs(P, Q)
    M, k, m = P.shape[0], P.shape[1], Q.shape[1]
    if M == 0:
        return np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2))
    pa, pb = _edges(P)
    qa, qb = _edges(Q)
    # vertices of P vs edges of Q: (M,k,m)
    d1, c1 = _closest_on_segments(P[:, :, None, :], qa[:, None, :, :], qb[:, None, :, :])
    # vertices of Q vs edges of P: (M,m,k)
    d2, c2 = _closest_on_segments(Q[:, :, None, :], pa[:, None, :, :], pb[:, None, :, :])
    d1f, d2f = d1.reshape(M, -1), d2.reshape(M, -1)
    i1, i2 = d1f.argmin(axis=1), d2f.argmin(axis=1)
    rows = np.arange(M)
    best1, best2 = d1f[rows, i1], d2f[rows, i2]
    use1 = best1 <= best2
    dist = np.where(use1, best1, best2)
    p1 = P[rows, i1 // m]  # vertex of P
    q1 = c1.reshape(M, -1, 2)[rows, i1]  # its closest point on Q
    q2 = Q[rows, i2 // k]  # vertex of Q
    p2 = c2.reshape(M, -1, 2)[rows, i2]  # its closest point on P
    p_on = np.where(use1[:, None], p1, p2)
    q_on = np.where(use1[:, None], q1, q2)

    touch = _max_separation(P, Q) <= tol
    if np.any(touch):
        t = np.flatnonzero(touch)
        Pt, Qt = P[t], Q[t]
        # candidate common points: P vertices in/on Q, Q vertices in/on P, edge crossings
        p_in = _inside_convex(Pt, Qt, tol) | (d1[t].min(axis=2) <= tol)  # (T,k)
        q_in = _inside_convex(Qt, Pt, tol) | (d2[t].min(axis=2) <= tol)  # (T,m)
        xpts, xok = _edge_intersections(Pt, Qt, tol)
        cand = np.concatenate([Pt, Qt, xpts], axis=1)
        ok = np.concatenate([p_in, q_in, xok], axis=1)
        j = ok.argmax(axis=1)
        common = cand[np.arange(t.size), j]
        # fallback (separation within tol but no exact common point): midpoint of closest pair
        none = ~ok.any(axis=1)
        common[none] = 0.5 * (p_on[t][none] + q_on[t][none])
        dist = dist.copy()
        dist[t] = 0.0
        p_on[t] = common
        q_on[t] = common
    return dist, p_on, q_on


def pairwise_footprint_distance(corners_a, corners_b) -> np.ndarray:
    """Footprint-to-footprint distance, m, between every A rectangle and every B rectangle.

    corners_a : (A, 4, 2), corners_b : (B, 4, 2) (e.g. from :func:`footprint_corners`).
    Returns (A, B), 0 where the footprints touch or overlap. Memory is O(A*B).
    """
    ca = np.asarray(corners_a, float)
    cb = np.asarray(corners_b, float)
    A, B = ca.shape[0], cb.shape[0]
    if A == 0 or B == 0:
        return np.zeros((A, B))
    P = np.repeat(ca, B, axis=0)  # (A*B,4,2), a-major
    Q = np.tile(cb, (A, 1, 1))
    d, _, _ = convex_distance(P, Q)
    return d.reshape(A, B)


def ccw_polygon(points) -> np.ndarray:
    """The polygon's vertices (k,2) in counter-clockwise order (reversed if given clockwise)."""
    pts = np.asarray(points, float).reshape(-1, 2)
    x, y = pts[:, 0], pts[:, 1]
    area2 = float((x * np.roll(y, -1) - np.roll(x, -1) * y).sum())
    return pts[::-1].copy() if area2 < 0 else pts.copy()


def pad_polygons(polys) -> np.ndarray:
    """Polygons of different vertex counts as one (P,K,2) CCW array, padded by repeating the last vertex."""
    polys = [ccw_polygon(pg) for pg in polys]
    k = max(len(pg) for pg in polys)
    return np.stack([np.vstack([pg, np.repeat(pg[-1:], k - len(pg), 0)]) for pg in polys])


def ring_walls(rings):
    """Segments and inward normals of an allowed area given as rings, each oriented so that the area
    lies to its left (exterior CCW, holes CW). Returns (a, b, inward)."""
    a = np.concatenate([np.asarray(r, float)[:-1] if np.allclose(r[0], r[-1]) else np.asarray(r, float)
                        for r in rings])
    b = np.concatenate([np.roll(np.asarray(r, float)[:-1] if np.allclose(r[0], r[-1]) else np.asarray(r, float),
                                -1, axis=0) for r in rings])
    d = b - a
    keep = np.hypot(d[:, 0], d[:, 1]) > 1e-9
    a, b, d = a[keep], b[keep], d[keep]
    inward = np.stack([-d[:, 1], d[:, 0]], -1) / np.hypot(d[:, 0], d[:, 1])[:, None]
    return a, b, inward


def near_any(points: np.ndarray, centres: np.ndarray, radius_m: float) -> np.ndarray:
    """(N,) bool: which ``points`` (N, 2) lie within ``radius_m`` of any of ``centres`` (M, 2).

    First each point is tried against the centres just before and after it along the axis the
    centres spread most on (usually enough when they are spread along a road); only the points
    this does not settle go to a k-d tree over all centres. Same distances (sqrt(dx^2 + dy^2)) and
    the same test as the k-d tree alone, so the same answer."""
    points, centres = np.asarray(points, float).reshape(-1, 2), np.asarray(centres, float).reshape(-1, 2)
    N, M = len(points), len(centres)
    if N == 0 or M == 0:
        return np.zeros(N, bool)
    ax = int(np.ptp(centres[:, 1]) > np.ptp(centres[:, 0]))
    order = np.argsort(centres[:, ax], kind="stable")
    i = np.searchsorted(centres[order, ax], points[:, ax])
    near = np.zeros(N, bool)
    for j in (np.maximum(i - 1, 0), np.minimum(i, M - 1)):
        d = points - centres[order[j]]
        near |= np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) <= radius_m
    rest = np.flatnonzero(~near)
    if len(rest):
        dist, _ = cKDTree(centres).query(points[rest], k=1, distance_upper_bound=radius_m * (1 + 1e-9))
        near[rest] = dist <= radius_m
    return near


def box_gap(lo_a, hi_a, lo_b, hi_b):
    """Gap between M pairs of axis-aligned boxes ``[lo_a, hi_a]`` and ``[lo_b, hi_b]`` ((M, 2) corners each):
    returns (distance (M,), unit direction (M, 2) from b towards a; zero where they overlap)."""
    lo_a, hi_a, lo_b, hi_b = (np.asarray(x, float) for x in (lo_a, hi_a, lo_b, hi_b))
    sep = np.where(lo_a > hi_b, lo_a - hi_b, np.where(lo_b > hi_a, hi_a - lo_b, 0.0))  # signed, b -> a
    n = np.hypot(sep[:, 0], sep[:, 1])
    return n, sep / np.maximum(n, 1e-12)[:, None]
