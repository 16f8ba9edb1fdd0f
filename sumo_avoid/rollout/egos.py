"""Who the plug-in drives: egos are taken over when they depart, retired at their goal or when
they leave the network on their own; the run is over when every ego is done. With a controller
that leaves the egos to SUMO (``Needs(drives=False)``) they are taken over as egos (recorded,
scored, retired at their goal) but none is ever driven: the loop senses, controls and moves nobody."""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.config import FieldError
from sumo_avoid.road.polyline import polyline_point_at
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import EgoTask


class EgoBook:
    def __init__(self, ego_ids, road, *, goal=None, goals=None, goal_tolerance_m: float, cruise_speed_mps: float,
                 uses_goals: bool = True, follow_routes: bool = True, drives: bool = True, turn_radius_m: float = 0.0):
        self.ids = frozenset(ego_ids)
        self.road = road
        self.goal = goal  # every ego's goal: [x, y], an edge id, or None: the end of each ego's route path
        self.goal_of = dict(goals or {})  # ego id -> its own goal ([x, y] or edge id), before ``goal``
        self.goal_tolerance_m = goal_tolerance_m
        self.cruise_speed_mps = cruise_speed_mps
        self.uses_goals = uses_goals
        self.follow_routes = follow_routes  # SUMO keeps each ego on its route's lanes (not in an arena)
        self.drives = drives  # the plug-in moves the egos; False: SUMO's driver does (controller "sumo")
        self.turn_radius_m = turn_radius_m  # the egos' smallest turning radius (0: none, they may turn on the spot)
        self.detours: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {}  # ego -> (its route, the one it drives)
        self.goals: dict[str, tuple[float, float]] = {}  # ego id -> goal (x, y), m (egos with a goal)
        self.active: dict[str, EgoTask] = {}  # driven now, in take-over order
        self.tasks: dict[str, EgoTask] = {}  # every ego taken over (for the metrics)
        self.finished: set[str] = set()
        # egos SUMO drives: those whose goal is their route's end, when each was last seen, and those SUMO
        # took out there (ego id -> time of its last recorded step, s): they reached it (metrics.basic)
        self._route_end: set[str] = set()
        self._seen: dict[str, float] = {}
        self.arrivals: dict[str, float] = {}

    def new(self, departed) -> list[str]:
        """The egos among the vehicles SUMO just inserted."""
        return [v for v in departed if v in self.ids]

    def take_over(self, sim, vid: str) -> EgoTask:
        info = sim.take_over(vid, drive=self.drives)
        edges = self._round_uturns(sim, vid, info)
        path, links, limits, lanes = self.road.route(edges, depart_lane=info.lane_index, vclass=info.vclass)
        if not self.follow_routes:  # an arena: the net is only a canvas, its junctions and limits are no rules
            links, limits = (), None
        goal = self._goal_point(vid, edges, path, links)
        if not self.drives and self._goal_is_route_end(vid, edges):
            self._route_end.add(vid)
        if self.uses_goals:
            self.goals[vid] = (float(goal[0]), float(goal[1]))
        task = EgoTask(vid, goal, path, self.cruise_speed_mps, links, limits, lanes, info.width_m, info.length_m,
                       info.vclass, _walkways(self.road))
        self.active[vid] = task
        self.tasks[vid] = task
        if self.follow_routes and self.drives:
            sim.follow_route(task)
        return task

    def _round_uturns(self, sim, vid: str, info) -> list[str]:
        """The ego's route, or where it has a U-turn, the fastest route round it to the same last edge
        (:mod:`sumo_avoid.road.uturns`: a car with a turning radius does not turn on the spot), given to
        SUMO too and said in its log. An ego SUMO drives turns as SUMO's drivers do; one with a goal point, or
        a goal edge the detour misses, keeps its route."""
        edges = list(info.route_edges)
        if not self.drives or not self.follow_routes or self.turn_radius_m <= 0.0:
            return edges
        new = self.road.without_uturns(edges, info.vclass)
        goal = self.goal_of.get(vid, self.goal)
        if new is None or (goal is not None and not (isinstance(goal, str) and goal in new)):
            return edges  # a goal point, or a goal edge the detour would miss: the route it was given
        if not sim.set_route(vid, new):
            return edges
        sim.note(f"sumo-avoid: ego '{vid}' drives round the U-turn(s) on its route (a car does not turn on the "
                 f"spot): {len(edges)} -> {len(new)} edges, to the same last edge {new[-1]}")
        self.detours[vid] = (tuple(edges), tuple(new))
        return list(new)

    def _goal_point(self, vid: str, edges: list[str], path: np.ndarray, links) -> np.ndarray:
        """(2,) goal of one ego: its point, or where its route path leaves its goal edge (the stop
        line of the junction link after that edge; the path's end on the last edge), or the path's end.
        Raises FieldError (naming the scenario key) for a goal edge that is not on the ego's route."""
        key = f"ego.goals.{vid}" if vid in self.goal_of else "ego.goal"
        goal = self.goal_of.get(vid, self.goal)
        if goal is None or (isinstance(goal, str) and not self.uses_goals):
            return np.asarray(path[-1], float)
        if not isinstance(goal, str):
            return np.asarray(goal, float)
        if goal not in edges:
            shown = " ".join(edges[:12]) + (f" ... ({len(edges)} edges)" if len(edges) > 12 else "")
            raise FieldError(key, f"an edge on the route SUMO gave ego '{vid}' ({shown})", goal)
        k = edges.index(goal)
        if k == len(edges) - 1:
            return np.asarray(path[-1], float)
        return np.asarray(polyline_point_at(path, links[k].s_stop_m), float)

    def _goal_is_route_end(self, vid: str, edges: list[str]) -> bool:
        """The ego's goal is the end of its route: no goal given, or its route's last edge."""
        goal = self.goal_of.get(vid, self.goal)
        return goal is None or (isinstance(goal, str) and bool(edges) and goal == edges[-1])

    def never_departed(self) -> list[str]:
        """Egos SUMO never inserted (not taken over), sorted."""
        return sorted(self.ids - set(self.tasks))

    def retire(self, sim, snap: Snapshot) -> list[str]:
        """Egos gone from the network on their own, then those whose centre is within the goal
        tolerance (taken out of SUMO); both are done. An ego SUMO drives whose goal is its route's end
        reaches it also when SUMO takes it out there (``arrivals``): SUMO's driver is told no lane to
        end on, only the route, and arrives on whichever lane it drove (the goal point lies on one)."""
        gone = [v for v in self.active if v not in snap.index]
        present = [v for v in self.active if v in snap.index]
        if not self.drives:
            arrived = sim.arrived()
            self.arrivals.update((v, self._seen[v]) for v in gone if v in self._route_end and v in arrived)
            self._seen.update((v, snap.time_s) for v in present)
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
        """The egos the plug-in moves this step (none when SUMO drives them)."""
        return tuple(v for v in self.active if v in snap.index) if self.drives else ()

    def all_done(self) -> bool:
        return len(self.finished) == len(self.ids) and not self.active


def _walkways(road) -> frozenset:
    """The net's sidewalks and walking areas (none for a road that does not list its elements)."""
    elements = getattr(road, "elements", None)
    return elements.walkways if elements is not None else frozenset()
