"""Polylines (route reference paths): arc length, point at s, projection, and the route's direction
at many vehicles at once. Pure numpy; shared by sensing, control and metrics."""
from __future__ import annotations

from bisect import bisect_left, bisect_right

import numpy as np


def _as_path(path) -> np.ndarray:
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    if len(p) == 0:
        raise ValueError("empty polyline")
    return p


def _cumlen(p: np.ndarray) -> np.ndarray:
    seg = np.hypot(*np.diff(p, axis=0).T) if len(p) > 1 else np.zeros(0)
    return np.concatenate([[0.0], np.cumsum(seg)])


def arc_lengths(path) -> np.ndarray:
    """(P,) arc length, m, at each vertex of a (P,2) polyline (0 at the first)."""
    return _cumlen(_as_path(path))


def polyline_length(path) -> float:
    """Total arc length of a (P,2) polyline, m."""
    return float(_cumlen(_as_path(path))[-1])


def polyline_point_at(path, s_m: float) -> np.ndarray:
    """Point at arc length ``s_m`` along the polyline (clamped to [0, length]) -> (2,)."""
    p = _as_path(path)
    cum = _cumlen(p)
    s = float(np.clip(s_m, 0.0, cum[-1]))
    return np.array([np.interp(s, cum, p[:, 0]), np.interp(s, cum, p[:, 1])])


def path_frames(path, cum, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points, unit tangents (the chord from s - 0.25 m to s + 0.25 m) and unit left normals, each (N,2), of
    polyline ``path`` (with arc lengths ``cum``) at arc lengths ``s``."""
    def at(x):
        return np.column_stack([np.interp(x, cum, path[:, 0]), np.interp(x, cum, path[:, 1])])
    tan = at(s + 0.25) - at(s - 0.25)
    tan /= np.maximum(np.hypot(tan[:, 0], tan[:, 1]), 1e-9)[:, None]
    return at(s), tan, np.column_stack([-tan[:, 1], tan[:, 0]])


def polyline_project(path, point) -> float:
    """Arc length of the point of the polyline nearest to ``point`` (m)."""
    p = _as_path(path)
    q = np.asarray(point, dtype=float).reshape(2)
    if len(p) == 1:
        return 0.0
    a, b = p[:-1], p[1:]
    d = b - a
    l2 = np.einsum("ij,ij->i", d, d)
    t = np.where(l2 > 0, np.einsum("ij,ij->i", q - a, d) / np.where(l2 > 0, l2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    foot = a + t[:, None] * d
    dist2 = np.einsum("ij,ij->i", foot - q, foot - q)
    k = int(np.argmin(dist2))
    return float(_cumlen(p)[k] + t[k] * np.sqrt(l2[k]))


def polyline_project_many(path, points) -> np.ndarray:
    """Arc lengths (N,) of the points of the polyline nearest to each of ``points`` (N, 2)."""
    p = _as_path(path)
    q = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(p) == 1 or len(q) == 0:
        return np.zeros(len(q))
    a, d = p[:-1], p[1:] - p[:-1]
    l2 = np.einsum("ij,ij->i", d, d)
    rel = q[:, None, :] - a[None]  # (N, S, 2)
    t = np.clip(np.einsum("nsk,sk->ns", rel, d) / np.where(l2 > 0, l2, 1.0), 0.0, 1.0) * (l2 > 0)
    gap = rel - t[..., None] * d[None]
    k = np.argmin(np.einsum("nsk,nsk->ns", gap, gap), axis=1)
    rows = np.arange(len(q))
    return _cumlen(p)[k] + t[rows, k] * np.sqrt(l2[k])


def _window(cum: list, s_m: float, window_m: float) -> tuple[int, int]:
    """Vertex range [lo, hi) of the part of a polyline (vertex arc lengths ``cum``) within
    ``window_m`` of arc length ``s_m``, with the vertices that bound it."""
    return max(0, bisect_right(cum, s_m - window_m) - 1), min(len(cum), bisect_left(cum, s_m + window_m) + 1)


def polyline_track(path, points, s_start: float | None = None, window_m: float = 30.0) -> np.ndarray:
    """Arc lengths (N,) of consecutive positions of one vehicle along ``path``: each point is
    projected on the part of the path within ``window_m`` of the previous one's arc length (the
    first: of ``s_start``, or on the whole path), so a route that comes back past itself (a
    turnaround, a loop, a roundabout) is followed branch by branch instead of jumping.

    Every point's foot and squared distance on every segment are computed at once (as
    :func:`polyline_project_many` computes them); only the choice of the nearest segment inside
    the window, which depends on the previous point, is a loop. The window's arc length is summed
    from its first vertex, as a projection on the window alone would sum it."""
    p = _as_path(path)
    q = np.asarray(points, dtype=float).reshape(-1, 2)
    out = np.zeros(len(q))
    cum = _cumlen(p)
    cum_l, last = cum.tolist(), len(p)
    if len(q) == 1 and s_start is not None:  # one step of a vehicle followed live: its window only
        lo, hi = _window(cum_l, s_start, window_m)
        return np.array([float(cum[lo] + polyline_project_many(p[lo:hi], q)[0])])
    if len(p) == 1 or len(q) == 0:
        return out
    a, d = p[:-1], p[1:] - p[:-1]
    l2 = np.einsum("ij,ij->i", d, d)
    seg_len = np.sqrt(l2)
    rel = q[:, None, :] - a[None]  # (N, S, 2)
    t = np.clip(np.einsum("nsk,sk->ns", rel, d) / np.where(l2 > 0, l2, 1.0), 0.0, 1.0) * (l2 > 0)
    gap = rel - t[..., None] * d[None]
    dist2 = np.einsum("nsk,nsk->ns", gap, gap)
    seg = np.hypot(*d.T).tolist()  # the segment lengths _cumlen sums
    rows = np.arange(len(q))
    k_all = np.argmin(dist2, axis=1)  # nearest segment of the whole path, and the arc length there
    s_all = cum[k_all] + t[rows, k_all] * seg_len[k_all]
    s_win = (cum[0] + s_all).tolist()  # the same as a window that spans the whole path
    s_all = s_all.tolist()
    prev = s_start
    for i in range(len(q)):
        if prev is None:
            prev = s_all[i]
            out[i] = prev
            continue
        lo, hi = _window(cum_l, prev, window_m)
        if hi - lo < 2:
            if hi <= lo:  # no vertex in the window (a start beyond the end; a zero window on a repeated vertex)
                raise ValueError("empty polyline")
            prev = cum_l[lo]
        elif lo == 0 and hi == last:
            prev = s_win[i]
        else:
            k = lo + int(np.argmin(dist2[i, lo:hi - 1]))
            along = 0.0
            for j in range(lo, k):  # in order, as _cumlen sums the window
                along += seg[j]
            prev = float(cum[lo] + (along + t[i, k] * seg_len[k]))
        out[i] = prev
    return out


def route_segments(paths):
    """The egos' route paths as padded segment arrays for :func:`route_directions`: (rows with a
    path, segment starts (P, S, 2), segment vectors (P, S, 2), squared lengths (P, S)); NaN pads."""
    ok = [k for k, p in enumerate(paths) if p is not None and len(p) > 1]
    S = max([len(paths[k]) - 1 for k in ok], default=0)
    a = np.full((len(ok), S, 2), np.nan)
    b = np.full((len(ok), S, 2), np.nan)
    for i, k in enumerate(ok):
        p = np.asarray(paths[k], float)
        a[i, :len(p) - 1], b[i, :len(p) - 1] = p[:-1], p[1:]
    ab = b - a
    return ok, a, ab, (ab**2).sum(-1)


def route_directions(paths, pos, heading, segments=None) -> np.ndarray:
    """(E,) rad: direction of the segment of each ego's route path nearest to it (its heading if it
    has no path). Vectorised over egos: paths padded to one (E, S) segment array, which a caller
    may pass in precomputed (``segments = route_segments(paths)``) while the egos stay the same."""
    out = np.asarray(heading, float).copy()
    ok, a, ab, L2 = route_segments(paths) if segments is None else segments
    if not ok:
        return out
    rel = np.asarray(pos, float)[ok][:, None, :] - a
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip((rel * ab).sum(-1) / L2, 0.0, 1.0)
    d2 = ((rel - t[..., None] * ab) ** 2).sum(-1)
    d2 = np.where(np.isfinite(d2) & (L2 > 1e-18), d2, np.inf)
    seg = np.take_along_axis(ab, d2.argmin(axis=1)[:, None, None], axis=1)[:, 0]
    out[ok] = np.arctan2(seg[:, 1], seg[:, 0])
    return out


def polyline_tangent(path, point):
    """At the path's point nearest to ``point``: (arc length s, that point (2,), unit tangent (2,)),
    the tangent pointing from the path's point at s to the one 1 m further along it."""
    s = polyline_project(path, point)
    a = polyline_point_at(path, s)
    d = polyline_point_at(path, s + 1.0) - a
    return s, a, d / max(np.hypot(d[0], d[1]), 1e-12)


#: A turn sharper than this (cosine between consecutive segments) turns the line back on itself: more than 90
#: degrees, its next segment runs against the way it came in.
SPUR_COS = 0.0
#: An excursion that comes back past where it turned within this much line is a spur, m.
SPUR_REACH_M = 50.0
#: The line that replaces a spur rejoins the way back this many metres ahead per metre across.
SPUR_SLOPE = 2.0


def cut_spurs(points, reach_m: float = SPUR_REACH_M, cos_back: float = SPUR_COS,
              slope: float = SPUR_SLOPE) -> tuple[np.ndarray, np.ndarray]:
    """(points (P,2), keep (P,) bool): a (P,2) polyline (no duplicate points) without its out-and-back
    spurs. A spur starts at a vertex where the line turns back (consecutive segments at a cosine below
    ``cos_back``) and comes back past it, moving the way it came in, within ``reach_m`` of line. The
    excursion is skipped: the line leaves the way in level with where the way back starts (that point
    replaces the turning vertex) and goes straight to the first point of the way back that lies
    ``slope`` times as far ahead as across (it replaces the vertex before it); the vertices in between
    are dropped (keep False, so every kept vertex keeps its index). OSM-derived nets have spurs where an
    edge's lanes are laid apart: a 0.29 m edge whose lane 1 lies 12 m behind its lane 2 (unseen
    Colonias, 376317858#4), where a lane change on it sent the path 12 m back and round again, and the
    car stood at the hairpin for good. A U-turn, which never comes back past its turning point, is kept."""
    p = np.array(points, float).reshape(-1, 2)
    keep = np.ones(len(p), bool)
    seg = np.diff(p, axis=0)
    n = np.hypot(*seg.T) if len(seg) else np.zeros(0)
    u = seg / np.maximum(n, 1e-12)[:, None]
    i = 1
    while i < len(p) - 1:
        cut = _spur(p, u, n, i, reach_m, slope) if u[i - 1] @ u[i] < cos_back else None
        if cut is None:
            i += 1
            continue
        a, j, q = cut
        p[i] = a
        keep[i] = np.hypot(*(a - p[i - 1])) > 1e-9  # (the way back starts behind the way in's last vertex)
        keep[i + 1:j - 1] = False
        if np.hypot(*(q - p[j])) > 1e-9:
            p[j - 1] = q
        else:  # it rejoins at vertex j itself
            keep[j - 1] = False
        i = j
    return p, keep


def _spur(p, u, n, i: int, reach_m: float, slope: float):
    """(a, j, q) for a spur that turns back at vertex i (:func:`cut_spurs`): the point a on the way in
    level with the start of the way back, and q on its segment j-1 -> j where the line rejoins it; None
    where the line does not come back past vertex i within ``reach_m`` (no spur)."""
    ahead = u[i - 1]
    along = np.concatenate([[0.0], np.cumsum(n[i:])])  # line from vertex i to vertex i + k
    back = np.flatnonzero((along[:-1] <= reach_m) & (u[i:] @ ahead > 0.0))
    if not len(back) or not ((p[i:] - p[i]) @ ahead > 0.0)[: int(np.searchsorted(along, reach_m, "right"))].any():
        return None
    r = i + int(back[0])  # the way back starts at vertex r
    t_a = min(max(float((p[r] - p[i - 1]) @ ahead) / max(n[i - 1], 1e-12), 0.0), 1.0)
    a = p[i - 1] + t_a * (p[i] - p[i - 1])
    for j in range(r + 1, len(p)):
        if along[j - 1 - i] > reach_m:
            return None
        if u[j - 1] @ ahead <= 0.0:
            continue
        t = np.minimum(np.arange(1, int(np.ceil(n[j - 1] / 0.05)) + 1) * 0.05 / max(n[j - 1], 1e-12), 1.0)[:, None]
        pts = p[j - 1] + t * (p[j] - p[j - 1]) - a
        fwd, across = pts @ ahead, np.abs(pts[:, 0] * ahead[1] - pts[:, 1] * ahead[0])
        ok = np.flatnonzero((fwd > 0.0) & (fwd >= slope * across))
        if len(ok):
            return a, j, a + pts[ok[0]]
    return None


#: A jog: the line steps aside by more than JOG_MIN_M within JOG_REACH_M of line, more steeply than
#: JOG_STEEP (across per metre ahead: 20 degrees; a bend's polygon is far flatter), and goes on within
#: JOG_PARALLEL_RAD of the way it came in. It is eased into a ramp at JOG_SLOPE.
JOG_MIN_M = 0.2
JOG_REACH_M = 4.0
JOG_STEEP = 0.36
JOG_SLOPE = 0.05
JOG_PARALLEL_RAD = 0.2


def ease_jogs(points, reach_m: float = JOG_REACH_M, slope: float = JOG_SLOPE, min_m: float = JOG_MIN_M,
              parallel_rad: float = JOG_PARALLEL_RAD, steep: float = JOG_STEEP) -> tuple[np.ndarray, np.ndarray]:
    """(points (Q,2), where (P,) int): a (P,2) polyline (no duplicate points) with its jogs eased, and for each
    input vertex the index of the output vertex that stands for it. A jog steps aside by a across (> ``min_m``)
    within ``reach_m`` of line from vertex i to vertex j, steeper than ``steep``, the lines before i and after j
    within ``parallel_rad`` of parallel. It becomes a ramp at ``slope`` centred on the step: from a point on the
    way in, through the step's midpoint, to a point on the way out, each end half the length the step needs at
    ``slope`` from the step (at most half their segments). Vertices i to j - 1 stand for the midpoint (what
    begins there, a junction's stop line, begins at the step), vertex j for the ramp's end. OSM-derived nets
    shift a whole road sideways at a point: Berlin's Doerpfeldstrasse, clusterJ1_J2, joins two lanes 1.57 m
    apart by a 1.6 m internal lane at right angles to both; a car cannot step aside there, and the ego that tried
    swung 0.8 m into the tram lane beside (``phi_wall`` 0.53 m on every seed). No ramp keeps a 1.8 m car inside
    two 3.2 m lanes 1.57 m apart at the step itself: centred, it is 0.09 m out on either side for a moment."""
    p = np.array(points, float).reshape(-1, 2)
    seg = np.diff(p, axis=0)
    n = np.hypot(*seg.T) if len(seg) else np.zeros(0)
    u = seg / np.maximum(n, 1e-12)[:, None]
    cum = np.concatenate([[0.0], np.cumsum(n)])
    out, where = [p[:1]], np.zeros(len(p), np.int64)
    count, i = 1, 1
    while i < len(p):
        jog = _jog_end(p, u, cum, i, reach_m, steep, min_m, np.cos(parallel_rad)) if i < len(p) - 2 else None
        if jog is None:
            out.append(p[i:i + 1])
            where[i], count, i = count, count + 1, i + 1
            continue
        j, across, ahead = jog
        half = min(0.5 * (across / slope - ahead), 0.5 * n[i - 1], 0.5 * n[j])
        a, b = p[i] - half * u[i - 1], p[j] + half * u[j]
        out.append(np.stack([a, 0.5 * (a + b), b]))
        where[i:j], where[j], count, i = count + 1, count + 2, count + 3, j + 1
    return np.concatenate(out), where


def _jog_end(p, u, cum, i: int, reach_m: float, steep: float, min_m: float, cos_parallel: float):
    """(j, across, ahead) of a jog that starts at vertex i (:func:`ease_jogs`): the vertex it ends at, how far it
    steps aside and how far on, m; None where there is none."""
    for j in range(i + 1, len(p) - 1):
        if cum[j] - cum[i] > reach_m:
            return None
        if u[i - 1] @ u[j] < cos_parallel:
            continue
        r = p[j] - p[i]
        across, ahead = abs(u[i - 1, 0] * r[1] - u[i - 1, 1] * r[0]), float(u[i - 1] @ r)
        if across > min_m and across > steep * max(ahead, 0.0):
            return j, across, ahead
    return None
