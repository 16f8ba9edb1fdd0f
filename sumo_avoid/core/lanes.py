"""The lanes along an ego's reference path, in its route frame (SPEC §5): for an arc length s,
where the lanes of the ego's own direction lie across the path (d of each lane centre, positive
left), the corridor they span [d_lo, d_hi] and which lane a lateral offset d falls in.

Built from :class:`~sumo_avoid.core.types.LanePiece` records (``EgoTask.lanes``); pure numpy.
The corridor holds the lanes of the ego's direction only: a two-way road's centre line and the
edge of the road are its bounds, and inside a junction the internal lane the route takes, widened
by ``JUNCTION_MARGIN_M`` on each side (a junction is open tarmac; a turning car's corners sweep
past its lane's width) with ramps of ``JUNCTION_RAMP_M`` at its entry and exit. Lanes that do not
continue the route end in a taper over the last ``TAPER_M`` before the junction (at most half the
edge), so the bound leads the car into the lane that continues instead of ending in a step.
The corridor is piecewise linear in s (breakpoints, ``np.interp``).
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.types import LanePiece


#: Lanes that do not continue the route narrow down to the route's lane over this length, m.
TAPER_M = 30.0
#: Inside a junction the route's internal lane is widened by this much on each side, m.
JUNCTION_MARGIN_M = 0.75
#: ... reached over this distance from the junction's entry and exit, m.
JUNCTION_RAMP_M = 3.0
_EPS = 1e-6


def _is_internal(piece: LanePiece) -> bool:
    return piece.edge.startswith(":")


class RouteLanes:
    """Vectorised look-ups over one path's lane pieces (read-only)."""

    def __init__(self, pieces: tuple[LanePiece, ...]):
        if not pieces:
            raise ValueError("a path needs at least one lane piece")
        self.pieces = tuple(pieces)
        self.s_start = np.array([p.s_start_m for p in pieces])
        self.s_end = np.array([p.s_end_m for p in pieces])
        pts: list[tuple[float, float, float]] = []  # (s, d_lo, d_hi) breakpoints in order of s
        n = len(pieces)
        for k, p in enumerate(pieces):
            w = np.asarray(p.widths_m)
            b0 = _bounds(p.offsets_start_m, w)
            b1 = _bounds(p.offsets_end_m, w)
            a, b = p.s_start_m, p.s_end_m
            if _is_internal(p):
                pts += [(a, *b0), (b, *b1)]
                continue
            pts.append((a, *b0))
            nxt = pieces[k + 1] if k + 1 < n else None
            if nxt is not None and _is_internal(nxt) and b - a > _EPS:  # the lanes that end taper off
                lane = (float(p.offsets_end_m[p.lane]) - 0.5 * w[p.lane], float(p.offsets_end_m[p.lane]) + 0.5 * w[p.lane])
                t0 = max(a, b - min(TAPER_M, 0.5 * (b - a)))
                f = (t0 - a) / (b - a)
                pts += [(t0, *((1 - f) * np.asarray(b0) + f * np.asarray(b1))), (b, *lane)]
            else:
                pts.append((b, *b1))
        s = np.array([q[0] for q in pts])
        s = np.maximum.accumulate(s + _EPS * np.arange(len(s)))  # strictly increasing: steps become steep ramps
        self._s = s
        self._lo = np.array([q[1] for q in pts])
        self._hi = np.array([q[2] for q in pts])
        self._widen = _junction_widening(self.pieces)

    def piece_index(self, s) -> np.ndarray:
        """(N,) index of the piece holding each arc length (clipped to the first/last piece)."""
        return np.clip(np.searchsorted(self.s_start, np.asarray(s, float), side="right") - 1, 0, len(self.pieces) - 1)

    def corridor(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(d_lo (N,), d_hi (N,)): the right and left bounds of the ego's lanes at arc lengths s, m."""
        s = np.atleast_1d(np.asarray(s, float))
        m = self._widen(s)
        return np.interp(s, self._s, self._lo) - m, np.interp(s, self._s, self._hi) + m

    def lane_at(self, s: float, d: float) -> tuple[str, int, bool]:
        """(edge id, lane index, inside) of the lane whose centre is nearest to (s, d); ``inside`` is
        False when d lies outside the corridor."""
        k = int(self.piece_index([s])[0])
        p = self.pieces[k]
        span = p.s_end_m - p.s_start_m
        f = float(np.clip((s - p.s_start_m) / span, 0.0, 1.0)) if span > 0 else 0.0
        o = (1 - f) * np.asarray(p.offsets_start_m) + f * np.asarray(p.offsets_end_m)
        lo, hi = self.corridor([s])
        return p.edge, int(np.argmin(np.abs(o - d))), bool(lo[0] <= d <= hi[0])

    def boundary_segments(self, s_from: float, s_to: float) -> np.ndarray:
        """(S, 2, 2) the corridor's right and left bounds between two arc lengths as segments in
        (s, d), one per breakpoint interval: the right bound's S/2 segments first, then the left's."""
        if s_to <= s_from:
            return np.zeros((0, 2, 2))
        inner = self._s[(self._s > s_from) & (self._s < s_to)]
        extra = self._widen.breaks(s_from, s_to)
        s = np.unique(np.concatenate([[s_from, s_to], inner, extra]))
        lo, hi = self.corridor(s)
        a = np.stack([s[:-1], lo[:-1]], -1), np.stack([s[1:], lo[1:]], -1)
        b = np.stack([s[:-1], hi[:-1]], -1), np.stack([s[1:], hi[1:]], -1)
        return np.concatenate([np.stack(a, 1), np.stack(b, 1)])


def _bounds(offsets, w) -> tuple[float, float]:
    o = np.asarray(offsets, float)
    return float((o - 0.5 * w).min()), float((o + 0.5 * w).max())


class _junction_widening:  # noqa: N801 (a callable table)
    """m(s): JUNCTION_MARGIN_M inside each run of internal pieces, ramping from 0 at its ends."""

    def __init__(self, pieces):
        runs, start = [], None
        for p in pieces:
            if _is_internal(p) and start is None:
                start = p.s_start_m
            if not _is_internal(p) and start is not None:
                runs.append((start, p.s_start_m))
                start = None
        if start is not None:
            runs.append((start, pieces[-1].s_end_m))
        self.runs = np.array(runs, float).reshape(-1, 2)

    def __call__(self, s: np.ndarray) -> np.ndarray:
        out = np.zeros(len(s))
        for a, b in self.runs:
            ramp = max(min(JUNCTION_RAMP_M, 0.5 * (b - a)), _EPS)
            out = np.maximum(out, JUNCTION_MARGIN_M * np.clip(np.minimum(s - a, b - s) / ramp, 0.0, 1.0))
        return out

    def breaks(self, s_from: float, s_to: float) -> np.ndarray:
        pts = []
        for a, b in self.runs:
            ramp = min(JUNCTION_RAMP_M, 0.5 * (b - a))
            pts += [a, a + ramp, b - ramp, b]
        pts = np.asarray(pts, float)
        return pts[(pts > s_from) & (pts < s_to)]
