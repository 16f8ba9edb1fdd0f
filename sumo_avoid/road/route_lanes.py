"""The lanes along an ego's reference path, in its route frame (SPEC §5): for an arc length s,
the corridor [d_lo, d_hi] the lanes of the ego's own direction span across the path (d positive
left) -- those its vehicle class may use (``LanePiece.allowed``: a car's corridor ends at the
sidewalk, the bike lane, the bus lane).

Built from :class:`~sumo_avoid.road.route.LanePiece` records (``EgoTask.lanes``); pure numpy.
The corridor holds the lanes of the ego's direction only: a two-way road's centre line and the
edge of the road are its bounds, and inside a junction the internal lane the route takes, widened
by ``JUNCTION_MARGIN_M`` on each side (a junction is open tarmac; a turning car's corners sweep
past its lane's width) with ramps of ``JUNCTION_RAMP_M`` at its entry and exit, but never over the
kerb of a sidewalk or walking area (:attr:`LanePiece.kerb_room_m`: people walk there); where the net lays an
oncoming lane of another edge over the ego's lanes, the corridor ends at that lane's border
(:attr:`LanePiece.narrowing_m`, :mod:`~sumo_avoid.road.overlaps`). Lanes that do not
continue the route end in a taper over the last ``TAPER_M`` before the junction (at most half the
edge), so the bound leads the car into the lane that continues instead of ending in a step.
The corridor is piecewise linear in s (breakpoints, ``np.interp``).
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.road.route import LanePiece, lane_bounds

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
        self._starts = np.array([p.s_start_m for p in self.pieces])
        pts: list[tuple[float, float, float]] = []  # (s, d_lo, d_hi) breakpoints in order of s
        n = len(pieces)
        for k, p in enumerate(pieces):
            w, ok = np.asarray(p.widths_m), p.usable()
            b0 = lane_bounds(p.offsets_start_m, w, ok)
            b1 = lane_bounds(p.offsets_end_m, w, ok)
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
        self._widen_s, self._widen_m = _junction_widening(self.pieces)
        room = np.array([p.kerb_room_m for p in self.pieces], float).reshape(-1, 2)
        self._kerb = room if np.isfinite(room).any() else None  # (pieces, 2) right, left; None: no walkway near
        # (the oncoming pass is built for an oncoming lane on the left: on the right, in left-hand traffic, none is lent)
        opp = [(q.s_start_m, q.s_end_m, 0.0 if _is_internal(q) or q.opposite_right else q.opposite_m) for q in self.pieces]
        self._opp_s = np.maximum.accumulate(np.array([x for a, b, _ in opp for x in (a, b)]) + _EPS * np.arange(2 * n))
        self._opp_w = np.array([w for _, _, w in opp for _ in (0, 1)])
        self._narrow = _narrowing(self.pieces)

    def opposite(self, s) -> np.ndarray:
        """(N,) width of the oncoming lane beside the ego's lanes (on their left) at arc lengths s that an
        overtaking pass may borrow (0: none; a junction has none; left-hand traffic has it on the right), m."""
        return np.interp(np.atleast_1d(np.asarray(s, float)), self._opp_s, self._opp_w)

    def corridor(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(d_lo (N,), d_hi (N,)): the right and left bounds of the ego's lanes at arc lengths s, m."""
        s = np.atleast_1d(np.asarray(s, float))
        m_lo, m_hi = self.widening(s)
        lo, hi = np.interp(s, self._s, self._lo) - m_lo, np.interp(s, self._s, self._hi) + m_hi
        if self._narrow is None:
            return lo, hi
        at, right, left = self._narrow
        return lo + np.interp(s, at, right), hi - np.interp(s, at, left)

    def widening(self, s) -> tuple[np.ndarray, np.ndarray]:
        """(right (N,), left (N,)): how far the corridor at arc lengths s is widened beyond the lanes on
        each side inside a junction, m (``JUNCTION_MARGIN_M``, never over the kerb of a walkway)."""
        s = np.atleast_1d(np.asarray(s, float))
        m = np.interp(s, self._widen_s, self._widen_m, left=0.0, right=0.0) if len(self._widen_s) else np.zeros(len(s))
        if self._kerb is None:
            return m, m
        k = np.clip(np.searchsorted(self._starts, s, side="right") - 1, 0, len(self.pieces) - 1)
        return np.minimum(m, self._kerb[k, 0]), np.minimum(m, self._kerb[k, 1])


    def lanes_end_s(self, s: float) -> float:
        """Arc length where the lanes of the edge at s that do not continue the route start to taper
        off (the corridor's taper, see the module doc), or where the edge ends if nothing follows it:
        a car in such a lane must be out of it, or stopped, by then."""
        k = self._index(s)
        while k + 1 < len(self.pieces) and self.pieces[k + 1].edge == self.pieces[k].edge:
            k += 1
        p = self.pieces[k]
        if k + 1 < len(self.pieces) and _is_internal(self.pieces[k + 1]) and p.s_end_m - p.s_start_m > _EPS:
            return max(p.s_start_m, p.s_end_m - min(TAPER_M, 0.5 * (p.s_end_m - p.s_start_m)))
        return p.s_end_m

    def lane_at(self, s: float, d: float) -> tuple[str, int] | None:
        """(SUMO edge id, lane index) of the lane of the ego's direction nearest to (s, d), or None
        when d is outside the corridor at s (off the route: in an oncoming lane, off the road)."""
        lo, hi = self.corridor([s])
        if not lo[0] <= d <= hi[0]:
            return None
        p, centres = self.centres(s)
        return p.edge, int(np.argmin(np.abs(centres - d)))

    def _index(self, s: float) -> int:
        """Index of the piece at arc length s."""
        return max(0, min(int(np.searchsorted(self._starts, s, side="right")) - 1, len(self.pieces) - 1))

    def centres(self, s: float) -> tuple[LanePiece, np.ndarray]:
        """(the piece at arc length s, d of every lane centre of its edge there (by lane index), m)."""
        p = self.pieces[self._index(s)]
        f = 0.0 if p.s_end_m - p.s_start_m <= _EPS else min(max((s - p.s_start_m) / (p.s_end_m - p.s_start_m), 0.0), 1.0)
        return p, (1.0 - f) * np.asarray(p.offsets_start_m) + f * np.asarray(p.offsets_end_m)


def _narrowing(pieces) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Breakpoints (s, right, left) of how far oncoming lanes of other edges move the corridor's borders in
    (:attr:`LanePiece.narrowing_m`, 0 on the other pieces), or None when no piece has any."""
    if not any(p.narrowing_m for p in pieces):
        return None
    pts = []
    for p in pieces:
        pts += list(p.narrowing_m) or [(p.s_start_m, 0.0, 0.0), (p.s_end_m, 0.0, 0.0)]
    s = np.maximum.accumulate(np.array([q[0] for q in pts]) + _EPS * np.arange(len(pts)))
    return s, np.array([q[1] for q in pts]), np.array([q[2] for q in pts])


def _junction_widening(pieces) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints (s, m) of the widening m(s): JUNCTION_MARGIN_M inside each run of internal
    pieces, ramping linearly from 0 at its entry and exit (piecewise linear, 0 elsewhere)."""
    runs, start = [], None
    for p in pieces:
        if _is_internal(p) and start is None:
            start = p.s_start_m
        if not _is_internal(p) and start is not None:
            runs.append((start, p.s_start_m))
            start = None
    if start is not None:
        runs.append((start, pieces[-1].s_end_m))
    s, m = [], []
    for a, b in runs:
        ramp = max(min(JUNCTION_RAMP_M, 0.5 * (b - a)), _EPS)
        s += [a, a + ramp, b - ramp, b]
        m += [0.0, JUNCTION_MARGIN_M, JUNCTION_MARGIN_M, 0.0]
    s = np.maximum.accumulate(np.asarray(s, float) + _EPS * np.arange(len(s)))
    return s, np.asarray(m, float)
