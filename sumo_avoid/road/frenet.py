"""Route frame (Frenet coordinates, SPEC §5): a point x <-> (s, d) along an ego's reference path,
velocities with the (1 - kappa d) factor, curvature smoothed over a few metres and the speed for
the road ahead. Pure numpy, vectorised over N points; docs/road_frame.md has the formulas.

The frame is the lane-centre polyline itself (so s is the route's arc length, d = 0 the lane centre)
with a continuous normal field: unit vertex normals are the bisectors of the adjacent segments'
normals (the end ones perpendicular to the end segments), interpolated linearly along each segment
and normalised, n(s). The inverse is x = P(s) + d n(s); the projection solves, per segment, for
the t in [0, 1] at which x - P(t) is parallel to the interpolated normal, a quadratic in t, so the
two maps are exact inverses (to rounding), at polyline corners too. The tangent t(s) is n(s)
turned 90 deg clockwise, so (t, n) is orthonormal and turns continuously through a corner.

Long segments get collinear vertices FAN_FACTOR * smooth_m inside their ends, so the normal turns
through a corner within that distance of it and is perpendicular on the rest of a straight.

Curvature does not come from that normal field: kappa(s) is the derivative of the heading smoothed
with a Gaussian over the polyline's vertex turns (sigma = smooth_m / sqrt(2 pi), the same peak as a
box of width smooth_m: a corner of angle phi peaks at phi / smooth_m), sampled on a grid of at most
0.5 m and linear in between."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.geometry import point_segment_distance
from sumo_avoid.road.frenet_compiled import project_window
from sumo_avoid.road.polyline import arc_lengths

#: Consecutive vertices closer than this are merged (near-duplicate points where lanes join), m.
MERGE_M = 0.01
#: Largest spacing of the curvature grid, m (finer when smooth_m is small: sigma / 2).
GRID_MAX_M = 0.5
#: Floor of (1 - kappa d) in the velocity maps (points at or past the centre of curvature).
MIN_SCALE = 0.1
#: The frame's normal turns through a polyline corner over FAN_FACTOR * smooth_m on either side.
FAN_FACTOR = 2.0
_T_EPS = 1e-9  # a root this far outside [0, 1] still belongs to the segment (the vertex is shared)
_BLOCK = 1_000_000  # points x segments per block of the unrestricted projection
_NEAREST = 8  # segments tried first in the unrestricted projection


def _cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _left(v):
    """v turned 90 deg counter-clockwise."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def _unit(v):
    return v / np.maximum(np.hypot(v[..., 0], v[..., 1]), 1e-300)[..., None]


def _vec(a, n=None) -> np.ndarray:
    a = np.atleast_1d(np.asarray(a, float))
    return a if n is None else np.broadcast_to(a, (n,))


def _merge_near_duplicates(p: np.ndarray) -> np.ndarray:
    keep = [0]
    for i in range(1, len(p)):
        if np.hypot(*(p[i] - p[keep[-1]])) >= MERGE_M:
            keep.append(i)
    if keep[-1] != len(p) - 1 and len(keep) > 1:  # the route's end point stays exact
        keep[-1] = len(p) - 1
    return p[keep]


def _split_long_segments(p: np.ndarray, fan_m: float) -> np.ndarray:
    """Collinear vertices ``fan_m`` inside both ends of every segment longer than 2 fan_m, so that
    the normal turns through a corner over at most fan_m on either side and is perpendicular on
    the rest of a long straight."""
    e = np.diff(p, axis=0)
    f = fan_m / np.hypot(e[:, 0], e[:, 1])
    out = [p[:1]]
    for i in range(len(e)):
        if f[i] < 0.5:
            out.append(p[i] + np.outer([f[i], 1.0 - f[i]], e[i]))
        out.append(p[i + 1:i + 2])
    return np.concatenate(out)


def _range_reduce(ufunc, values: np.ndarray, lo, hi, empty: float) -> np.ndarray:
    """ufunc over values[lo : hi + 1] for every pair (lo, hi), ``empty`` where the range is empty.
    One ``ufunc.reduceat`` over the ranges sorted by start: O(G + total range length)."""
    G = len(values)
    lo, hi = np.clip(lo, 0, G).astype(np.int64), np.clip(hi, -1, G - 1).astype(np.int64)
    ok = lo <= hi
    out = np.full(lo.shape, empty)
    if not ok.any():
        return out
    order = np.argsort(np.where(ok, lo, G), kind="stable")
    a = np.append(values, empty)  # a[G] serves the empty ranges and hi + 1 == G
    idx = np.stack([np.where(ok, lo, G)[order], np.where(ok, hi + 1, G)[order]], -1).ravel()
    out[order] = ufunc.reduceat(a, idx)[::2]
    return np.where(ok, out, empty)


@dataclass(frozen=True, eq=False)
class RouteFrame:
    """The route frame of one reference polyline; build it with :meth:`from_polyline`. Arrays are
    read-only in spirit (eq=False: frames compare by identity, the arrays make == ambiguous)."""

    vertices: np.ndarray  # (P, 2) m, the reference polyline: near-duplicates merged, long segments split
    s_vertex: np.ndarray  # (P,) m, arc length at each vertex
    seg_vec: np.ndarray  # (P-1, 2) m, segment vectors
    seg_len: np.ndarray  # (P-1,) m
    normals: np.ndarray  # (P, 2) unit vertex normals (bisectors), left of the direction of travel
    turn_rad: np.ndarray  # (P,) signed turn at each vertex, > 0 left (0 at the two ends)
    smooth_m: float  # the curvature's smoothing length (Gaussian sigma = smooth_m / sqrt(2 pi)), m
    grid_s0_m: float  # arc length of the curvature grid's first node, m (< 0: the grid overhangs)
    grid_step_m: float  # curvature grid spacing, m
    kappa_grid: np.ndarray  # (G,) signed curvature at the grid nodes, 1/m

    @classmethod
    def from_polyline(cls, points, smooth_m: float = 5.0) -> RouteFrame:
        """The frame of a (P, 2) polyline of lane centres, m (corners, near-duplicate points and long
        straight segments allowed). ``smooth_m`` > 0: length over which headings are smoothed for
        the curvature, m."""
        if not smooth_m > 0:
            raise ValueError(f"smooth_m must be > 0, got {smooth_m}")
        v = _merge_near_duplicates(np.asarray(points, float).reshape(-1, 2))
        if len(v) < 2:
            raise ValueError(f"a route frame needs a polyline longer than {MERGE_M} m")
        v = _split_long_segments(v, FAN_FACTOR * smooth_m)
        e = np.diff(v, axis=0)
        length = np.hypot(e[:, 0], e[:, 1])
        s_v = arc_lengths(v)
        n_seg = _left(e / length[:, None])
        turn = np.zeros(len(v))
        turn[1:-1] = np.arctan2(_cross(e[:-1], e[1:]), np.einsum("ij,ij->i", e[:-1], e[1:]))
        half = turn[1:-1, None] / 2  # the bisector: the incoming normal turned by half the turn
        normals = np.concatenate([n_seg[:1], np.cos(half) * n_seg[:-1] + np.sin(half) * _left(n_seg[:-1]),
                                  n_seg[-1:]])
        sigma = smooth_m / np.sqrt(2.0 * np.pi)  # the peak of a box of width smooth_m
        step, reach = min(GRID_MAX_M, sigma / 2.0), 4.0 * sigma
        n_grid = int(np.ceil((s_v[-1] + 2.0 * reach) / step)) + 1
        kappa = np.zeros(n_grid)
        j = np.flatnonzero(turn)
        if len(j):  # kappa = sum over vertex turns of turn * Gaussian(s - s_vertex): d/ds of the
            k = int(np.ceil(reach / step)) + 1  # smoothed heading, exact at the nodes
            idx = np.rint((s_v[j] + reach) / step).astype(np.int64)[:, None] + np.arange(-k, k + 1)
            u = (-reach + step * idx - s_v[j][:, None]) / sigma
            w = turn[j][:, None] * np.exp(-0.5 * u * u) / (sigma * np.sqrt(2.0 * np.pi))
            ok = (idx >= 0) & (idx < n_grid)
            np.add.at(kappa, idx[ok], w[ok])
        return cls(v, s_v, e, length, normals, turn, float(smooth_m), -reach, step, kappa)

    # ----------------------------------------------------------------------------- the frame
    @property
    def length_m(self) -> float:
        """Arc length of the reference path, m."""
        return float(self.s_vertex[-1])

    def _locate(self, s):
        """Segment index (N,) and segment parameter t (N,) of arc lengths s; t < 0 before the
        start and t > 1 past the end (extrapolation along the end segments)."""
        i = np.clip(np.searchsorted(self.s_vertex, s, side="right") - 1, 0, len(self.seg_len) - 1)
        return i, (s - self.s_vertex[i]) / self.seg_len[i]

    def _point_normal(self, s):
        i, t = self._locate(s)
        p = self.vertices[i] + t[:, None] * self.seg_vec[i]
        tc = np.clip(t, 0.0, 1.0)[:, None]
        return p, _unit((1.0 - tc) * self.normals[i] + tc * self.normals[i + 1])

    def normal_at(self, s) -> np.ndarray:
        """(N, 2) unit normal n(s), left of the direction of travel."""
        return self._point_normal(_vec(s))[1]

    def tangent_at(self, s) -> np.ndarray:
        """(N, 2) unit tangent t(s) = n(s) turned 90 deg clockwise."""
        n = self.normal_at(s)
        return np.stack([n[:, 1], -n[:, 0]], axis=-1)

    def heading_at(self, s) -> np.ndarray:
        """(N,) direction of t(s), rad CCW from +x."""
        n = self.normal_at(s)
        return np.arctan2(-n[:, 0], n[:, 1])

    def curvature_at(self, s) -> np.ndarray:
        """(N,) signed curvature of the smoothed path, 1/m (> 0 turning left); 0 far off the ends."""
        g = self.grid_s0_m + self.grid_step_m * np.arange(len(self.kappa_grid))
        return np.interp(_vec(s), g, self.kappa_grid, left=0.0, right=0.0)

    def to_xy(self, s, d) -> np.ndarray:
        """(N, 2) points x = P(s) + d n(s), m."""
        s = _vec(s)
        p, n = self._point_normal(s)
        return p + _vec(d, len(s))[:, None] * n

    # ----------------------------------------------------------------------------- projection
    def _candidates(self, x: np.ndarray, seg: np.ndarray):
        """All (s, d) with x = P(s) + d n(s) on segments ``seg`` (N, W) and on the extensions of
        the end segments: (N, 2W + 2) each, NaN where no solution."""
        a, e, na = self.vertices[seg], self.seg_vec[seg], self.normals[seg]
        m = self.normals[seg + 1] - na  # n(t) = na + t m, not unit
        w = x[:, None, :] - a
        qa = -_cross(e, m)  # cross(w - t e, na + t m) = qa t^2 + qb t + qc = 0
        qb = _cross(w, m) - _cross(e, na)
        qc = _cross(w, na)
        with np.errstate(all="ignore"):
            q = -0.5 * (qb + np.copysign(np.sqrt(qb * qb - 4.0 * qa * qc), qb))
            t = np.stack([q / qa, qc / q], axis=-1)  # the stable pair of roots (N, W, 2)
        ok = np.isfinite(t) & (t >= -_T_EPS) & (t <= 1.0 + _T_EPS)
        t = np.clip(np.where(ok, t, 0.0), 0.0, 1.0)
        n = _unit((1.0 - t)[..., None] * na[:, :, None] + t[..., None] * self.normals[seg + 1][:, :, None])
        r = w[:, :, None] - t[..., None] * e[:, :, None]
        d = np.where(ok, np.einsum("nwkc,nwkc->nwk", r, n), np.nan).reshape(len(x), -1)
        s = np.where(ok, self.s_vertex[seg][..., None] + t * self.seg_len[seg][..., None], np.nan)
        t0, t1 = self.seg_vec[0] / self.seg_len[0], self.seg_vec[-1] / self.seg_len[-1]
        r0, r1 = x - self.vertices[0], x - self.vertices[-1]
        a0, a1 = r0 @ t0, r1 @ t1
        ext_s = np.stack([np.where(a0 < 0, a0, np.nan), np.where(a1 > 0, self.length_m + a1, np.nan)], -1)
        ext_d = np.stack([_cross(t0, r0), _cross(t1, r1)], -1)
        return np.concatenate([s.reshape(len(x), -1), ext_s], 1), np.concatenate([d, ext_d], 1)

    @staticmethod
    def _pick(s_c, d_c, lo=None, hi=None):
        """The candidate of smallest |d| (within [lo, hi] if given): (s, d), NaN where none."""
        if lo is not None:
            s_c = np.where((s_c >= lo[:, None]) & (s_c <= hi[:, None]), s_c, np.nan)
        cost = np.where(np.isnan(s_c) | np.isnan(d_c), np.inf, np.abs(d_c))
        k = np.argmin(cost, axis=1)[:, None]
        found = np.isfinite(np.take_along_axis(cost, k, 1)[:, 0])
        s = np.where(found, np.take_along_axis(s_c, k, 1)[:, 0], np.nan)
        return s, np.where(found, np.take_along_axis(d_c, k, 1)[:, 0], np.nan)

    def _project_all(self, x: np.ndarray):
        """Projection onto the whole path, exact: the solution's foot P(s) lies on its segment at
        distance |d| from x, so only segments no farther from x than the best |d| found on the
        _NEAREST nearest segments can hold a better one; those are solved in a second pass."""
        n_seg = len(self.seg_len)
        rows = max(1, _BLOCK // n_seg)
        s, d = np.empty(len(x)), np.empty(len(x))
        for b in range(0, len(x), rows):
            xb = x[b:b + rows]
            dist = point_segment_distance(xb, self.vertices[:-1], self.vertices[1:])[0]
            k = min(_NEAREST, n_seg)
            sb, db = self._pick(*self._candidates(xb, np.argpartition(dist, k - 1, axis=1)[:, :k]))
            bound = np.where(np.isnan(db), np.inf, np.abs(db)) * (1.0 + 1e-9) + 1e-9
            w = int((dist <= bound[:, None]).sum(axis=1).max())
            if w > k:
                near = np.argpartition(dist, w - 1, axis=1)[:, :w] if w < n_seg else \
                    np.broadcast_to(np.arange(n_seg), (len(xb), n_seg))
                sb, db = self._pick(*self._candidates(xb, near))
            s[b:b + rows], d[b:b + rows] = sb, db
        return s, d

    def to_frenet(self, xy, s_hint=None, window_m: float = 30.0):
        """(s (N,), d (N,)) of points xy (N, 2): s the arc length of the projection (< 0 before the
        start, > length past the end), d the signed offset along n(s), positive LEFT. Where several
        projections exist (the inside of a bend, a path that passes near itself) the one of smallest
        |d|; with ``s_hint`` (N,) only s in [s_hint - window_m, s_hint + window_m] (a point with
        none there falls back to the whole path)."""
        x = np.asarray(xy, float).reshape(-1, 2)
        if s_hint is None or len(x) == 0:
            return self._project_all(x)
        h = _vec(s_hint, len(x))
        lo, hi = h - window_m, h + window_m
        last = len(self.seg_len) - 1
        i0 = np.clip(np.searchsorted(self.s_vertex, lo, side="right") - 1, 0, last)
        i1 = np.clip(np.searchsorted(self.s_vertex, hi, side="right") - 1, 0, last)
        seg = np.minimum(i0[:, None] + np.arange(int((i1 - i0).max()) + 1), last)
        s, d = self._pick(*self._candidates(x, seg), lo, hi)
        miss = np.flatnonzero(np.isnan(s))
        if len(miss):
            s[miss], d[miss] = self._project_all(x[miss])
        return s, d

    def point_to_frenet(self, x: float, y: float, s_hint: float | None, window_m: float = 30.0) -> tuple[float, float]:
        """(s, d) of one point: :meth:`to_frenet` of ``[[x, y]]`` with ``[s_hint]`` (None: the whole path),
        the windowed search compiled (:func:`sumo_avoid.road.frenet_compiled.project_window`, the same result)
        where the window lies within the path (else, rarely, :meth:`to_frenet` itself)."""
        if s_hint is not None and (s_hint - window_m < 0.0 or s_hint + window_m > self.s_vertex[-1]):
            s, d = self.to_frenet(np.array([[x, y]], float), [s_hint], window_m)
            return float(s[0]), float(d[0])
        if s_hint is not None:
            s, d = project_window(self.vertices, self.normals, self.seg_vec, self.seg_len, self.s_vertex,
                                  float(x), float(y), float(s_hint), float(window_m))
            if not np.isnan(s):
                return s, d
        s, d = self._project_all(np.array([[x, y]], float))
        return float(s[0]), float(d[0])

    # ----------------------------------------------------------------------------- velocities
    def _frame_scale(self, s, d):
        s = _vec(s)
        n = self.normal_at(s)
        scale = np.maximum(1.0 - self.curvature_at(s) * _vec(d, len(s)), MIN_SCALE)
        return np.stack([n[:, 1], -n[:, 0]], axis=-1), n, scale

    def velocity_to_frenet(self, s, d, v_xy):
        """(s_dot (N,), d_dot (N,)) of velocities v_xy (N, 2), m/s, at (s, d): v = s_dot (1 - kappa d)
        t + d_dot n (SPEC §5), kappa = curvature_at(s); (1 - kappa d) floored at MIN_SCALE."""
        t, n, scale = self._frame_scale(s, d)
        v = np.asarray(v_xy, float).reshape(-1, 2)
        return np.einsum("ij,ij->i", v, t) / scale, np.einsum("ij,ij->i", v, n)

    def velocity_to_xy(self, s, d, s_dot, d_dot) -> np.ndarray:
        """(N, 2) velocities, m/s: s_dot (1 - kappa d) t(s) + d_dot n(s), the inverse of
        :meth:`velocity_to_frenet`."""
        t, n, scale = self._frame_scale(s, d)
        return (_vec(s_dot, len(scale)) * scale)[:, None] * t + _vec(d_dot, len(scale))[:, None] * n

    # ----------------------------------------------------------------------------- the road ahead
    def _grid_index(self, s, after: bool):
        """Index of the first grid node at or after s (``after``) or of the last one at or before s;
        may fall off the grid by one (the range queries clip)."""
        x = (np.clip(s, self.grid_s0_m - 1.0, self.grid_s0_m + self.grid_step_m * len(self.kappa_grid))
             - self.grid_s0_m) / self.grid_step_m
        return (np.ceil(x - 1e-9) if after else np.floor(x + 1e-9)).astype(np.int64)

    def max_abs_curvature_ahead(self, s, horizon_m) -> np.ndarray:
        """(N,) max |kappa| over [s, s + horizon_m], 1/m (exact for the grid's piecewise-linear
        kappa: the two ends and every node in between)."""
        s = _vec(s)
        end = s + np.maximum(_vec(horizon_m, len(s)), 0.0)
        inner = _range_reduce(np.maximum, np.abs(self.kappa_grid), self._grid_index(s, after=True),
                              self._grid_index(end, after=False), 0.0)
        return np.maximum(inner, np.maximum(np.abs(self.curvature_at(s)), np.abs(self.curvature_at(end))))

    def curve_speed_limit(self, s, v_mps, a_lat_max_mps2: float = 2.5, b_comf_mps2: float = 3.0):
        """(N,) speed for the road ahead from curvature, m/s (SPEC §5): the largest v at s from which
        the ego, braking at b_comf_mps2, reaches every s' ahead within its braking distance
        v_mps^2 / (2 b) at no more than v_curve(s') = sqrt(a_lat_max / |kappa(s')|):
            v_lim(s) = min over s' in [s, s + v_mps^2 / (2 b)] of sqrt(v_curve(s')^2 + 2 b (s' - s)).
        inf where nothing in that window asks for less (a straight road). Whether v_mps <= v_lim
        is the same as with the window over all s' >= s (points past the braking distance give at
        least v_mps); v_mps = inf gives that full envelope, a speed one may accelerate towards.
        a_lat_max_mps2 and b_comf_mps2 are scalars; s' runs over s, the window's end and the grid."""
        s = _vec(s)
        v = _vec(v_mps, len(s))
        a, b = float(a_lat_max_mps2), float(b_comf_mps2)
        with np.errstate(divide="ignore", invalid="ignore"):
            reach = np.where(np.isfinite(v), v * v / (2.0 * b), np.inf)
            end = s + reach
            g = self.grid_s0_m + self.grid_step_m * np.arange(len(self.kappa_grid))
            u = a / np.abs(self.kappa_grid) + 2.0 * b * g  # v_curve^2(s') + 2 b s' at the nodes
            lo, hi = self._grid_index(s, after=True), self._grid_index(end, after=False)
            to_end = hi >= len(g) - 1  # the window covers the rest of the grid: suffix minimum
            suffix = np.append(np.minimum.accumulate(u[::-1])[::-1], np.inf)
            nodes = np.where(to_end, suffix[np.clip(lo, 0, len(g))],
                             _range_reduce(np.minimum, u, np.where(to_end, len(g), lo), hi, np.inf))
            here = a / np.abs(self.curvature_at(s))
            there = np.where(np.isfinite(end), a / np.abs(self.curvature_at(np.where(np.isfinite(end), end, 0.0)))
                             + 2.0 * b * reach, np.inf)
            v2 = np.minimum(np.minimum(here, there), nodes - 2.0 * b * s)
        return np.sqrt(np.maximum(v2, 0.0))
