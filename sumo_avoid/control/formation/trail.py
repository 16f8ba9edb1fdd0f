"""The leader's recorded path, owned by :class:`~sumo_avoid.control.formation.formation.FormationController`:
the trail the followers follow when the formation is broken up (``broken = "trail"``)
and the way back for a follower lost in a pocket of the field after the leader has left."""
from __future__ import annotations

from collections import deque

import numpy as np


class LeaderTrail:
    """The leader's path (a point every 0.5 m) and the followers that follow it after the leader left."""

    def __init__(self, params):
        self.p = params  # FormationParams
        self.path = np.zeros((0, 3))  # the leader's path: x, y, arc length s (a point every 0.5 m)
        self._progress: dict[str, deque] = {}  # follower -> (time, distance to its goal) once the leader is done
        # follower -> how far it came along the leader's path while it follows it (_lost_goals); None once it
        # reached the path's end
        self._lost: dict[str, float | None] = {}

    def extend(self, pos) -> None:
        if not len(self.path):
            self.path = np.array([[pos[0], pos[1], 0.0]])
            return
        d = float(np.hypot(*(pos - self.path[-1, :2])))
        if d >= 0.5:
            self.path = np.vstack([self.path, [pos[0], pos[1], self.path[-1, 2] + d]])

    def points(self, back_m) -> np.ndarray:
        """(E, 2) points of the trail ``back_m`` (E,) metres behind its newest point (its first
        point if the trail is shorter)."""
        s = np.maximum(self.path[-1, 2] - np.asarray(back_m, float), 0.0)
        return np.column_stack([np.interp(s, self.path[:, 2], self.path[:, 0]),
                                np.interp(s, self.path[:, 2], self.path[:, 1])])

    def lost_goals(self, ids, pos, goals, t: float) -> np.ndarray:
        """Goals (E, 2) once the leader is at its goal: a follower that came less than ``lost_progress_m``
        nearer its own goal within ``lost_window_s`` is caught in a pocket of the field and from
        then on aims at the point
        ``spacing_m`` ahead on the leader's path (a way the leader drove) past the path's point nearest
        it (never behind where it was on the path), until that point would lie beyond the path's end;
        then at its goal again, for good."""
        p, out = self.p, np.array(goals, float)
        dist = np.hypot(*(out - pos).T)
        for k, vid in enumerate(ids):
            h = self._progress.setdefault(vid, deque())
            h.append((t, float(dist[k])))
            while h[0][0] < t - p.lost_window_s - 1e-9:
                h.popleft()
            if vid not in self._lost and h[-1][0] - h[0][0] >= p.lost_window_s - 1e-9 and h[0][1] - h[-1][1] < p.lost_progress_m:
                self._lost[vid] = 0.0
            if self._lost.get(vid) is not None:  # along the path, never back (its nearest point jumps)
                s = max(self._lost[vid], float(self.path[int(np.argmin(np.hypot(*(self.path[:, :2] - pos[k]).T))), 2]))
                if s + p.spacing_m < self.path[-1, 2]:
                    self._lost[vid] = s
                    out[k] = self.points([self.path[-1, 2] - s - p.spacing_m])[0]
                else:  # at the path's end: to its goal, for good (aiming back at the path makes it circle)
                    self._lost[vid] = None
        return out
