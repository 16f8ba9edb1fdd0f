"""Who the plug-in drives: egos are taken over when they depart, retired at their goal or when
they leave the network on their own; the run is over when every ego is done."""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import EgoTask


class EgoBook:
    def __init__(self, ego_ids, road, *, goal=None, goal_tolerance_m: float, cruise_speed_mps: float,
                 uses_goals: bool = True):
        self.ids = frozenset(ego_ids)
        self.road = road
        self.goal = goal  # [x, y] for every ego, or None: the end of each ego's route path
        self.goal_tolerance_m = goal_tolerance_m
        self.cruise_speed_mps = cruise_speed_mps
        self.uses_goals = uses_goals
        self.goals: dict[str, tuple[float, float]] = {}  # ego id -> goal (x, y), m (egos with a goal)
        self.active: dict[str, EgoTask] = {}  # driven now, in take-over order
        self.tasks: dict[str, EgoTask] = {}  # every ego taken over (for the metrics)
        self.finished: set[str] = set()

    def new(self, departed) -> list[str]:
        """The egos among the vehicles SUMO just inserted."""
        return [v for v in departed if v in self.ids]

    def take_over(self, sim, vid: str) -> EgoTask:
        info = sim.take_over(vid)
        path, links, limits, lanes = self.road.route(list(info.route_edges), depart_lane=info.lane_index)
        goal = np.asarray(self.goal if self.goal is not None else path[-1], float)
        if self.uses_goals:
            self.goals[vid] = (float(goal[0]), float(goal[1]))
        task = EgoTask(vid, goal, path, self.cruise_speed_mps, links, limits, lanes)
        self.active[vid] = task
        self.tasks[vid] = task
        return task

    def retire(self, sim, snap: Snapshot) -> list[str]:
        """Egos gone from the network on their own, then those whose centre is within the goal
        tolerance (taken out of SUMO); both are done."""
        gone = [v for v in self.active if v not in snap.index]
        present = [v for v in self.active if v in snap.index]
        done = []
        if self.uses_goals and present:  # one array operation for all egos
            gap = snap.pos[[snap.index[v] for v in present]] - np.array([self.goals[v] for v in present])
            done = [v for v, d in zip(present, np.hypot(gap[:, 0], gap[:, 1])) if d <= self.goal_tolerance_m]
        for vid in done:
            sim.release(vid)
        for vid in gone + done:
            self.active.pop(vid)
            self.finished.add(vid)
        return gone + done

    def driven(self, snap: Snapshot) -> tuple[str, ...]:
        return tuple(v for v in self.active if v in snap.index)

    def all_done(self) -> bool:
        return len(self.finished) == len(self.ids) and not self.active
