"""The reward of one step, per ego, from the quantities the run's metrics measure afterwards
(README "Metrics"), here on the snapshot just read, so that what an agent is trained for is what
the reports judge:

* progress: metres gained along the ego's route (its route frame's s, as ``goal_reached`` and the
  route's progress); ``goal`` once when it is retired at its goal;
* collisions: a new contact of the ego's footprint with another road user's (the ``collisions``
  metric's test, :func:`~sumo_avoid.core.geometry.convex_overlap`; one penalty per contact episode);
* violations: how far the footprint sticks out of the drivable area of its class (φ_wall's d; in an
  arena how far its centre is outside the walls), per second; metres driven facing a lane's traffic
  (``wrong_way_m``'s test, :meth:`~sumo_avoid.road.lane_index.LaneIndex.against`);
* comfort: |jerk| and |lateral acceleration| (``comfort``'s quantities, from the held speed and
  heading step to step), per second.

reward = progress_per_m x ds + goal x reached - collision x new contacts - off_road_per_m_s x outside x dt
- wrong_way_per_m x wrong-way metres - jerk_per_mps3_s x |jerk| x dt - lat_accel_per_mps2_s x |a_lat| x dt.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.geometry import convex_overlap, footprint_corners, wrap_angle
from sumo_avoid.road.walls import outside_distance as arena_outside_distance


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward's terms (all >= 0; a penalty's weight is subtracted)."""

    progress_per_m: float = 0.1  # per metre gained along the route
    goal: float = 10.0  # once, at the goal
    collision: float = 10.0  # per new contact
    off_road_per_m_s: float = 1.0  # per metre the footprint sticks out of the drivable area, per second
    wrong_way_per_m: float = 0.5  # per metre driven facing a lane's traffic
    jerk_per_mps3_s: float = 0.001  # per m/s^3 of |jerk|, per second
    lat_accel_per_mps2_s: float = 0.01  # per m/s^2 of lateral acceleration, per second

    def __post_init__(self):
        for name, value in vars(self).items():
            if not np.isfinite(value) or value < 0:
                raise ValueError(f"RewardWeights.{name}: a finite weight >= 0, got {value!r}")


@dataclass
class _Track:
    s_m: float | None = None
    speed_mps: float | None = None
    accel_mps2: float | None = None
    heading_rad: float | None = None
    pos: np.ndarray | None = None
    contacts: frozenset = frozenset()


class RewardTracker:
    """Each ego's previous step (for progress, contacts and comfort) and the reward of a new one."""

    def __init__(self, weights: RewardWeights, scene, step_s: float, vclass: dict[str, str]):
        self.w, self.scene, self.dt = weights, scene, step_s
        self.vclass = vclass  # ego id -> its SUMO vehicle class (its drivable area)
        self._tracks: dict[str, _Track] = {}

    def step(self, snap, vid: str, s_m: float | None, reached: bool) -> tuple[float, dict]:
        """(reward, its terms) of ego ``vid`` on ``snap``; ``s_m`` its route frame's arc length (None when
        it is no longer driven), ``reached`` retired at its goal this step."""
        tr = self._tracks.setdefault(vid, _Track())
        terms = {"progress_m": 0.0, "goal": float(reached), "new_contacts": 0, "off_road_m": 0.0,
                 "wrong_way_m": 0.0, "jerk_mps3": 0.0, "lat_accel_mps2": 0.0}
        row = snap.index.get(vid)
        if row is not None:
            if s_m is not None and tr.s_m is not None:
                terms["progress_m"] = s_m - tr.s_m
            contacts = self._contacts(snap, row)
            terms["new_contacts"] = len(contacts - tr.contacts)
            terms.update(self._road(snap, row, vid, tr))
            terms.update(self._comfort(snap, row, tr))
            tr.contacts, tr.pos, tr.heading_rad = contacts, snap.pos[row].copy(), float(snap.heading[row])
        tr.s_m = s_m if s_m is not None else tr.s_m
        w = self.w
        reward = (w.progress_per_m * terms["progress_m"] + w.goal * terms["goal"] - w.collision * terms["new_contacts"]
                  - w.off_road_per_m_s * terms["off_road_m"] * self.dt - w.wrong_way_per_m * terms["wrong_way_m"]
                  - w.jerk_per_mps3_s * abs(terms["jerk_mps3"]) * self.dt
                  - w.lat_accel_per_mps2_s * terms["lat_accel_mps2"] * self.dt)
        return float(reward), terms

    def forget(self, vid: str) -> None:
        self._tracks.pop(vid, None)

    @staticmethod
    def _contacts(snap, row: int) -> frozenset:
        """Ids of the road users whose footprint touches the ego's at ``row``."""
        half = 0.5 * np.hypot(snap.length, snap.width)
        gap = np.hypot(*(snap.pos - snap.pos[row]).T)
        near = np.flatnonzero((gap <= half + half[row] + 1e-9) & (np.arange(snap.n) != row))
        near = near[snap.same_level(row, near)]  # one passing over the other touches nothing (core.levels)
        if not len(near):
            return frozenset()
        corners = footprint_corners(snap.pos, snap.heading, snap.length, snap.width)
        hit = convex_overlap(np.repeat(corners[[row]], len(near), axis=0), corners[near])
        return frozenset(snap.ids[i] for i in near[hit])

    def _road(self, snap, row: int, vid: str, tr: _Track) -> dict:
        sc = self.scene
        pos = snap.pos[row]
        if sc.walls is not None:
            return {"off_road_m": float(arena_outside_distance(pos[None, :], sc.walls, sc.obstacles)[0])}
        corner = footprint_corners(pos[None, :], snap.heading[[row]], snap.length[[row]], snap.width[[row]])
        out = float(sc.road.footprint_outside_distance(corner, self.vclass.get(vid))[0])
        wrong = 0.0
        if tr.pos is not None:
            moved = float(np.hypot(*(pos - tr.pos)))
            h = tr.heading_rad
            mid = 0.5 * (pos + tr.pos)
            if moved > 0 and sc.road.lanes.against(mid[None, :], np.array([[np.cos(h), np.sin(h)]]))[0]:
                wrong = moved
        return {"off_road_m": out, "wrong_way_m": wrong}

    def _comfort(self, snap, row: int, tr: _Track) -> dict:
        v = float(np.hypot(*snap.vel[row]))
        out = {}
        if tr.speed_mps is not None:
            a = (v - tr.speed_mps) / self.dt
            if tr.accel_mps2 is not None:
                out["jerk_mps3"] = (a - tr.accel_mps2) / self.dt
            tr.accel_mps2 = a
            out["lat_accel_mps2"] = abs(v * float(wrap_angle(snap.heading[row] - tr.heading_rad)) / self.dt)
        tr.speed_mps = v
        return out
