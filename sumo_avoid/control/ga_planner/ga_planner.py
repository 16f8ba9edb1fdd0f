"""``ga_planner``: seed 004's radar-driven GA path planner with a pure-pursuit tracker (SPEC §4).

Per ego: a :class:`~sumo_avoid.planning.radar_map.RadarMap` collects the static returns of its own
radar (``ego.sensor = "radar"``: ``Observation.detections``, tracker memory included; no target
ids, no ground truth). With ``ego.sensor = "truth"`` the map is the scenario's obstacle polygons
sampled every ``map_cell_m`` along their edges, all known from the start (to separate perception
effects from planning); on a road, the footprints of the road users standing there at each step
(:func:`~sumo_avoid.planning.radar_map.standing_edges`). The GA (:mod:`sumo_avoid.planning.ga`) plans a path from the ego to its
goal:

* at take-over (trigger ``takeover``);
* when the radar reports an obstacle not seen before (``new_obstacle``: a return farther than
  ``new_obstacle_gap_m`` from every earlier one);
* when the rest of the current path comes closer than ``replan_margin_m`` to a known point
  (``clearance``);
* after the governor stopped the car and it backed up (``blocked``, see below);

the others at most every ``min_replan_interval_s`` (a pending trigger waits). Each replan is
warm-started from the rest of the previous best path. The path is tracked by pure pursuit
(:mod:`sumo_avoid.planning.pursuit`) forward only (the course within ``max_course_deg`` of the
heading); while the best path is not usable (closer than the safety radius to a known point) the
speed is capped at ``unusable_speed_mps``. A governor stops the car ``stop_gap_m`` before any known
point in the strip ahead of it (along its heading and its course), braking at
``governor_decel_mps2``, and never faster than the distance from its front to the nearest known
point within ``governor_cone_deg`` of the heading over ``governor_time_gap_s`` (the radar reveals an
obstacle's face a piece at a time: slow near what is known, the rest is likely beside it); stopped there, the car backs up for ``reverse_s``, nose turning towards the
path, and plans again. The governor keeps the danger-time layer from having to brake (its danger
time stays above ``governor_time_gap_s`` > the layer's 1 s): that layer holds full braking while
anything is within twice its standstill gap ahead, whatever the command, so a car it stopped
facing an obstacle can never back away. The layers (danger time, rules) still act on
the command.

Each plan is logged (``plans.csv``: time, trigger, generations, generation of the first usable
path, clearance, length, plan time, best fitness per generation, the path) with the map points
(``radar_map.csv``). Counters in metrics.json: ``stats_keys`` (``generations_to_usable``: mean over plans with a usable
path; ``plans_usable_within_20``: share of plans usable by generation 20). Plan times: timings.json only (not deterministic).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.control.road_view import FrenetScene, RoadView
from sumo_avoid.core.config import field_doc
from sumo_avoid.core.types import EgoTask, Keys, Observation
from sumo_avoid.road.polyline import arc_lengths, polyline_project
from sumo_avoid.planning import kernels
from sumo_avoid.planning.ga import GaParams, clearance, plan, resample
from sumo_avoid.planning.pursuit import aim_angle, arena_bounds, cone_gap, corridor_gap, pursuit_velocity, rest_of
from sumo_avoid.planning.radar_map import RadarMap, farther_than, sampled_edges, standing_edges, static_returns
from sumo_avoid.planning.corridor import (CLIP_SLACK_M, all_lanes_corridor, corridor_clip, follow_speed, in_frame,
                                         lane_centres, meeting_points, pick_lane, wall_points, whole_lanes)


@dataclass(frozen=True)
class GaPlannerParams(GaParams):
    map_cell_m: float = field_doc(2.0, positive=True, doc="the obstacle map keeps one point per square of this side, m")
    shadow_depth_m: float = field_doc(6.0, doc="a return also marks the line of sight behind it this deep, m")
    shadow_step_m: float = field_doc(2.0, doc="spacing of those shadow points, m (0 = no shadow)")
    face_half_width_m: float = field_doc(3.0, doc="a return also marks its obstacle's face this far either side "
                                                  "across the line of sight, m")
    static_speed_mps: float = field_doc(1.0, doc="returns estimated slower than this are static obstacles, m/s")
    new_obstacle_gap_m: float = field_doc(4.0, doc="a return farther than this from every earlier one is a new "
                                                   "obstacle (replan), m")
    replan_margin_m: float = field_doc(2.5, doc="replan when the rest of the path comes closer than this to a "
                                                "known obstacle point, m")
    min_replan_interval_s: float = field_doc(0.5, doc="shortest time between two plans of one ego, s")
    wall_margin_m: float = field_doc(4.0, doc="in an arena, waypoints keep this far inside the walls, m")
    lookahead_min_m: float = field_doc(6.0, doc="pure pursuit: smallest look-ahead distance, m")
    lookahead_time_s: float = field_doc(0.8, doc="pure pursuit: look-ahead distance per unit speed, s")
    lat_accel_mps2: float = field_doc(2.0, doc="speed on the path's arcs and at its corners: lateral acceleration, m/s^2")
    decel_mps2: float = field_doc(3.0, doc="braking planned before the path's corners, m/s^2")
    unusable_speed_mps: float = field_doc(2.0, doc="speed cap while the best path is not collision-free, m/s")
    max_course_deg: float = field_doc(80.0, doc="forward, the commanded direction stays within this angle of the heading, deg")
    stop_gap_m: float = field_doc(4.5, doc="governor: stop this far before a known obstacle point in the strip ahead, m")
    governor_decel_mps2: float = field_doc(2.0, doc="governor: braking it plans with, m/s^2")
    governor_time_gap_s: float = field_doc(1.5, positive=True, doc="governor: at most the distance from the front to "
                                                                    "the nearest known point in the cone ahead / this, s")
    governor_cone_deg: float = field_doc(35.0, doc="governor: the time gap counts known points within this angle "
                                                   "of the heading (unseen parts of an obstacle lie beside its seen ones), deg")
    corridor_margin_m: float = field_doc(1.0, doc="governor: the strip ahead is the car's width plus this either side, m")
    reverse_s: float = field_doc(3.0, doc="a car stopped by the governor facing away from its path backs up this long, s")
    reverse_speed_mps: float = field_doc(1.5, doc="speed of that manoeuvre, m/s")
    # --- on a road (no arena walls): planned in the route frame (s, d), docs/planner.md "The road case"
    road_horizon_m: float = field_doc(60.0, positive=True, doc="road: a plan ends this far ahead along the route "
                                                              "(or at the goal), m")
    road_replan_interval_s: float = field_doc(1.0, positive=True, doc="road: plan again at least this often "
                                                                      "(moving traffic, the horizon moves on), s")
    road_safety_radius_m: float = field_doc(1.4, doc="road: safety_radius_m (the car's half width 0.9 m + 0.5 m), m")
    road_replan_margin_m: float = field_doc(1.2, doc="road: replan_margin_m, m")
    road_wall_margin_m: float = field_doc(1.6, doc="road: paths keep this far inside the lanes of the ego's "
                                                   "direction (waypoints clipped; the bounds, moved out by "
                                                   "road_safety_radius_m - this, are obstacle points), m")
    road_wall_step_m: float = field_doc(2.0, positive=True, doc="road: spacing of the points on the lane bounds, m")
    road_init_spread_m: float = field_doc(1.5, doc="road: init_spread_m (across the road), m")
    road_mutation_sigma_m: float = field_doc(1.5, doc="road: mutation_sigma_m, m")
    road_face_half_width_m: float = field_doc(0.0, doc="road: face_half_width_m (none: a point blocks its lane), m")
    road_shadow_depth_m: float = field_doc(4.0, doc="road: shadow_depth_m (about a car's length), along the "
                                                    "lane beyond the point, not along the line of sight, m")
    road_memory_s: float = field_doc(20.0, doc="road: the map keeps only points a scan hit in this last time "
                                              "(traffic that stood and drove on leaves no obstacle), s")
    road_corridor_margin_m: float = field_doc(0.4, doc="road: corridor_margin_m of the governor's strip, m")
    road_sense_radius_m: float = field_doc(100.0, positive=True, doc="road: vehicles farther than this are "
                                                                    "left out of the plan, m")
    vru_margin_m: float = field_doc(1.0, doc="road: a person or cyclist (ground truth) counts as grown by this "
                                             "much on every side, m")
    road_follow_gap_m: float = field_doc(6.0, doc="road: a moving vehicle blocks its lane where the ego would be "
                                                  "closer than this (bumper to bumper) along the road, m")
    road_gap_headway_s: float = field_doc(1.0, doc="road: that gap grows by this x the speed difference, s")
    road_lane_free_m: float = field_doc(3.0, doc="road: a plan ends on a lane centre that keeps this far from "
                                                 "every obstacle point, m")
    road_follow_decel_mps2: float = field_doc(3.0, doc="road: behind a moving vehicle, the ego could stop at this "
                                                        "braking where the vehicle is now (it may hide a standing "
                                                        "obstacle), m/s^2")
    road_standstill_m: float = field_doc(3.0, doc="road: following a moving vehicle, gap kept at a stop, m")
    road_settle_m: float = field_doc(10.0, positive=True, doc="road: while no usable path is found, the car "
                                                             "steers back to its lane's centre over this distance, m")
    road_wait_gap_m: float = field_doc(12.0, doc="road: while no usable path is found, the car stops this far "
                                                 "before a known point in its strip ahead (room to steer out later), m")
    road_lane_tol_m: float = field_doc(0.2, doc="road: a static point blocks the whole lane it lies in unless it "
                                                "is within this + road_lane_tol_per_m x its range of a lane line, m")
    road_lane_tol_per_m: float = field_doc(0.0175, doc="road: see road_lane_tol_m (tan of the radar's 1 deg azimuth "
                                                       "step), m per m")
    road_static_min_cos: float = field_doc(0.3, doc="road: a return counts as standing only where the cosine of "
                                                    "the angle between its line of sight and the road exceeds this "
                                                    "(abeam, the radial speed of passing traffic is ~0)")

    def on_road(self) -> GaPlannerParams:
        """The parameters on a road: the ``road_*`` values in place of the field's, no cone governor."""
        return replace(self, safety_radius_m=self.road_safety_radius_m, replan_margin_m=self.road_replan_margin_m,
                       init_spread_m=self.road_init_spread_m, mutation_sigma_m=self.road_mutation_sigma_m,
                       face_half_width_m=self.road_face_half_width_m, shadow_depth_m=self.road_shadow_depth_m,
                       corridor_margin_m=self.road_corridor_margin_m, governor_cone_deg=0.0)


@dataclass
class _Ego:
    task: EgoTask
    map: RadarMap
    path: np.ndarray | None = None
    usable: bool = False
    s: float = 0.0
    last_plan_s: float = -np.inf
    pending: str = ""
    truth: bool = False  # no radar (ego.sensor = "truth"): the scenario's obstacles, all known
    standing: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # truth on a road: what stands now
    reverse_until_s: float = -np.inf
    reverse_turn: float = 0.0  # +1: back up turning the nose left, -1: right
    view: RoadView | None = None  # on a road: the route frame the plans are made in
    corridor: object = None  # on a road: s -> (d_lo, d_hi), the planner's walls (planning/corridor.py)
    path_sd: np.ndarray | None = None  # on a road: the best path's waypoints (s, d)
    now: float = 0.0
    pos: np.ndarray | None = None  # on a road: the centre at this step, m
    plans: list = field(default_factory=list)


class GaPlannerController(BaseController):
    plots = ("plans",)  # plans.png and convergence.png from its plan log (sumo_avoid.plots.PLOTS)
    stats_keys = Keys(("plans", "replans", "generations_to_usable", "generations_to_usable_max",  # stats()
                       "plans_usable_within_20", "plans_never_usable", "planner_reversals"))

    def __init__(self, params: GaPlannerParams, ctx):
        super().__init__(params, ctx)
        self.rng = ctx.rng()
        self.axle_m = ctx.rear_axle_m
        self.truth_points = sampled_edges(ctx.obstacles, params.map_cell_m)
        self.bounds = arena_bounds(ctx.walls, params.wall_margin_m)
        self.road = ctx.walls is None  # no arena: every ego plans in its route frame
        self.pr = params.on_road()
        self.egos: dict[str, _Ego] = {}
        self.log: list[dict] = []
        self.map_rows: list[tuple] = []
        self.reversals = 0
        kernels.warm()

    def add_ego(self, task: EgoTask) -> None:
        super().add_ego(task)
        road = self.road and bool(task.lanes)
        p = self.pr if road else self.p
        # on a road the shadow is cast along the lane at plan time (planning/corridor.py whole_lanes)
        self.egos[task.vid] = _Ego(task, RadarMap(p.map_cell_m, 0.0 if road else p.shadow_depth_m, p.shadow_step_m,
                                                  p.new_obstacle_gap_m, p.face_half_width_m, refine=road),
                                   view=RoadView(task) if road else None,
                                corridor=all_lanes_corridor(task.lanes) if road else None)

    def remove_ego(self, vid: str) -> None:
        super().remove_ego(vid)
        st = self.egos.pop(vid)
        self.map_rows.extend((vid, *r) for r in st.map.rows)

    # --- outputs ---------------------------------------------------------------------------
    def stats(self) -> dict:
        usable = [r["generation_usable"] for r in self.log if r["generation_usable"] >= 0]
        n = len(self.log)
        return {"plans": n, "replans": sum(r["trigger"] != "takeover" for r in self.log),
                "generations_to_usable": float(np.mean(usable)) if usable else None,
                "generations_to_usable_max": max(usable) if usable else None,
                "plans_usable_within_20": sum(g <= 20 for g in usable) / n if n else None,
                "plans_never_usable": n - len(usable), "planner_reversals": self.reversals}

    def tables(self) -> dict:
        rows = self.map_rows + [(v, *r) for v, st in self.egos.items() for r in st.map.rows]
        return {"plans": pd.DataFrame(self.log, columns=list(_LOG_COLUMNS)),
                "radar_map": pd.DataFrame(rows, columns=["ego", "time_s", "x", "y", "is_return"])}

    # --- planning ---------------------------------------------------------------------------
    def _params(self, st: _Ego) -> GaPlannerParams:
        return self.p if st.view is None else self.pr

    def _points(self, st: _Ego) -> np.ndarray:
        if st.truth:
            return self.truth_points if st.view is None else st.standing
        return st.map.points if st.view is None else st.map.seen_since(st.now - self.p.road_memory_s)[0]

    def _static_road(self, st: _Ego) -> tuple[np.ndarray, np.ndarray]:
        """On a road: (points (M, 2), the range each was measured at (M,)), what stands there."""
        if st.truth:
            return st.standing, np.hypot(*(st.standing - st.pos).T)
        return st.map.seen_since(st.now - self.pr.road_memory_s)

    def _trigger(self, st: _Ego, obs: Observation, vid: str, pos, t: float) -> str:
        p = self._params(st)
        st.truth = obs.detections is None
        if not st.truth:
            along = None if st.view is None or obs.route_heading is None else float(obs.route_heading[obs.index(vid)])
            pts, src = static_returns(obs, vid, p.static_speed_mps, along, p.road_static_min_cos)
            if st.map.add(src, pts, t) and st.path is not None:
                st.pending = st.pending or "new_obstacle"
        elif st.view is not None:  # ground truth on a road: the road users standing there now
            pts = standing_edges(obs.snapshot, int(obs.ego_rows[obs.index(vid)]), p.static_speed_mps,
                                 p.road_sense_radius_m, p.map_cell_m)
            new, st.standing = farther_than(pts, st.standing, p.new_obstacle_gap_m), pts
            if new and st.path is not None:
                st.pending = st.pending or "new_obstacle"
        if st.path is None:
            return "takeover"
        if not st.pending and len(self._points(st)):
            rest = rest_of(st.path, st.s, pos)
            if len(rest) > 1 and clearance(rest[None], self._points(st))[0] < p.replan_margin_m:
                st.pending = "clearance"
        if st.view is not None and not st.pending and t - st.last_plan_s >= p.road_replan_interval_s:
            st.pending = "horizon"
        if st.pending and t - st.last_plan_s >= p.min_replan_interval_s and t >= st.reverse_until_s:
            trig, st.pending = st.pending, ""
            return trig
        return ""

    def _plan(self, st: _Ego, vid: str, pos, t: float, trigger: str) -> None:
        warm = None if st.path is None else rest_of(st.path, st.s, pos)
        pts = self._points(st)
        t0 = time.perf_counter()
        res = plan(pos, st.task.goal, pts, self.p, self.rng, self.bounds, warm)
        ms = 1e3 * (time.perf_counter() - t0)
        st.path, st.usable, st.s, st.last_plan_s = res.path, res.usable, 0.0, t
        self._log(st, vid, t, trigger, res, res.path, ms)

    def _log(self, st: _Ego, vid: str, t: float, trigger: str, res, path_xy, ms: float) -> None:
        self.log.append({"ego": vid, "time_s": t, "trigger": trigger, "generations": res.generations,
                         "generation_usable": -1 if res.generation_usable is None else res.generation_usable,
                         "usable": res.usable, "clearance_m": res.clearance_m,
                         "path_length_m": float(arc_lengths(path_xy)[-1]), "known_points": len(st.map),
                         "plan_ms": ms, "best_fitness": ";".join(f"{f:.6g}" for f in res.best_fitness),
                         "path": ";".join(f"{x:.3f} {y:.3f}" for x, y in path_xy)})

    def _plan_road(self, st: _Ego, sc: FrenetScene, moving, vid: str, t: float, trigger: str) -> None:
        """One plan in the route frame: from the ego's (s, d) to a lane centre ``road_horizon_m``
        ahead (or the goal), around the known static points, the moving vehicles' meeting stretches
        and the lane bounds (planning/corridor.py); the path is mapped back to x-y every 2 m."""
        p, view = self.pr, st.view
        s0, d0 = sc.s, sc.d
        s_end = min(s0 + p.road_horizon_m, float(view.goal[0]))
        xy, ranges = self._static_road(st)
        sd, idx = in_frame(xy, st.pos, view.frame, s0, s_end, p.road_horizon_m + 20.0)
        static = whole_lanes(sd, ranges[idx], st.task.lanes, s0, p.road_lane_tol_m, p.road_lane_tol_per_m,
                             p.shadow_depth_m, p.shadow_step_m)
        # at least half its cruise speed: a car waiting for a gap accelerates into it (planned at a crawl,
        # the cars coming up behind block the next lane beside it, and the gap never comes)
        v_plan = max(float(sc.vel[0]), 0.5 * st.task.cruise_speed_mps)
        ahead = meeting_points(sc.o_pos[moving], sc.o_vel[moving], sc.o_length[moving], sc.o_width[moving], s0, d0,
                               v_plan, sc.length, p.road_follow_gap_m, s_end + 10.0, 1.0, 0.5 * sc.width + 0.6,
                               p.road_gap_headway_s)
        known = np.concatenate([static, ahead])
        if s_end >= float(view.goal[0]):
            goal = view.goal
        else:
            goal = np.array([s_end, pick_lane(lane_centres(st.task.lanes, s_end, usable_only=True), d0, s_end, known,
                                              p.road_lane_free_m)])
        walls = wall_points(st.corridor, s0 - 5.0, s_end + 10.0, p.road_wall_step_m,
                            p.road_safety_radius_m - p.road_wall_margin_m)
        pts = np.concatenate([known, walls])
        warm = None
        if st.path_sd is not None:
            rest = st.path_sd[st.path_sd[:, 0] > s0 + 1.0]
            warm = np.concatenate([[[s0, d0]], rest]) if len(rest) else None
        t0 = time.perf_counter()
        res = plan((s0, d0), goal, pts, p, self.rng, corridor_clip(st.corridor, p.road_wall_margin_m + CLIP_SLACK_M, s0, s_end), warm)
        ms = 1e3 * (time.perf_counter() - t0)
        # no usable path (traffic beside, no way past yet): back to the centre of the lane the ego
        # is in and wait there (the governor stops it road_wait_gap_m short of what blocks it)
        if res.usable:
            drive = res.path
        else:
            c = lane_centres(st.task.lanes, s0, usable_only=True)
            own = float(c[np.argmin(np.abs(c - d0))])
            drive = np.array([[s0, d0], [min(s0 + p.road_settle_m, s_end - 1.0), own], [s_end, own]])
        dense = resample(drive, max(2, int(np.ceil(arc_lengths(drive)[-1] / 2.0)) + 1))
        st.path_sd, st.usable, st.s, st.last_plan_s = drive, res.usable, 0.0, t
        st.path = np.concatenate([st.pos[None], view.frame.to_xy(dense[1:, 0], dense[1:, 1])])
        self._log(st, vid, t, trigger, res, view.frame.to_xy(res.path[:, 0], res.path[:, 1]), ms)

    # --- one step --------------------------------------------------------------------------
    def act(self, obs: Observation) -> np.ndarray:
        snap = obs.snapshot
        out = np.zeros((len(obs.ego_ids), 2))
        for k, (vid, row) in enumerate(zip(obs.ego_ids, obs.ego_rows)):
            st = self.egos[vid]
            pos = snap.pos[row]
            if st.view is not None:
                out[k] = self._road_step(st, obs, k, row, vid)
                continue
            trigger = self._trigger(st, obs, vid, pos, snap.time_s)
            if trigger:
                self._plan(st, vid, pos, snap.time_s, trigger)
            st.s = max(st.s, polyline_project(st.path, pos))
            out[k] = self._track(st, pos, float(snap.heading[row]), float(obs.ego_speed[k]), float(snap.length[row]),
                                 float(snap.width[row]), snap.time_s)
        return out

    def _road_step(self, st: _Ego, obs: Observation, k: int, row: int, vid: str) -> np.ndarray:
        """One step on a road: plan in the route frame, track, stay behind moving vehicles in the strip."""
        p, snap = self.pr, obs.snapshot
        pos, t = snap.pos[row], snap.time_s
        st.now, st.pos = t, np.asarray(pos, float)
        sc = st.view.scene(obs, row, p.road_sense_radius_m, p.vru_margin_m)
        moving = np.hypot(*sc.o_vel.T) >= p.static_speed_mps
        trigger = self._trigger(st, obs, vid, pos, t)
        if trigger:
            self._plan_road(st, sc, moving, vid, t, trigger)
        st.s = max(st.s, polyline_project(st.path, pos))
        v = self._track(st, pos, float(snap.heading[row]), float(obs.ego_speed[k]), float(snap.length[row]),
                        float(snap.width[row]), t)
        o_pos = sc.o_pos[moving]
        d_path = np.interp(o_pos[:, 0], st.path_sd[:, 0], st.path_sd[:, 1])
        v_follow = follow_speed(o_pos, sc.o_length[moving], sc.o_width[moving], sc.s,
                                np.vstack([np.full(len(o_pos), sc.d), d_path]), sc.length, sc.width,
                                p.road_corridor_margin_m, p.road_follow_decel_mps2, p.road_standstill_m)
        if not st.usable:  # waiting for a way past: keep room to steer out of the lane later
            gap = corridor_gap(self._points(st), pos, float(snap.heading[row]), 0.5 * sc.length,
                               0.5 * sc.width + p.corridor_margin_m)
            v_follow = min(v_follow, np.sqrt(2.0 * p.governor_decel_mps2 * max(gap - p.road_wait_gap_m, 0.0)))
        n = float(np.hypot(*v))
        return v * min(1.0, v_follow / n) if n > 1e-12 else v

    def _track(self, st: _Ego, pos, heading: float, speed: float, length: float, width: float, t: float) -> np.ndarray:
        """Pure pursuit, under a governor that stops the car ``stop_gap_m`` before a known point in
        its strip ahead (along its heading and along its course: turning sweeps the strip); stopped there,
        it backs up for ``reverse_s`` turning its nose towards the path, then plans again."""
        p = self._params(st)
        lookahead = max(p.lookahead_min_m, p.lookahead_time_s * abs(speed))
        alpha = aim_angle(st.path, st.s, pos, heading, lookahead)
        if t < st.reverse_until_s:
            return p.reverse_speed_mps * np.array([np.cos(heading + np.pi + st.reverse_turn * np.pi / 4),
                                                   np.sin(heading + np.pi + st.reverse_turn * np.pi / 4)])
        # the strip along the heading and along the course the car is turning to
        course = heading + float(np.clip(alpha, -np.radians(p.max_course_deg), np.radians(p.max_course_deg)))
        strips = (heading, course) if st.view is None else (course,)  # on a road: only where it steers to
        gap = min(corridor_gap(self._points(st), pos, h, 0.5 * length, 0.5 * width + p.corridor_margin_m)
                  for h in strips)
        v_stop = np.sqrt(2.0 * p.governor_decel_mps2 * max(gap - p.stop_gap_m, 0.0))
        near = cone_gap(self._points(st), pos, heading, 0.5 * length, np.radians(p.governor_cone_deg))
        v_gov = min(v_stop, near / p.governor_time_gap_s)
        if v_stop < 0.5 and abs(speed) < 0.3 and st.view is not None:  # blocked on a road: never back up, plan again
            st.pending = st.pending or "blocked"
        elif v_stop < 0.5 and abs(speed) < 0.3:  # blocked: back up, then plan again from there
            st.reverse_until_s, st.reverse_turn = t + p.reverse_s, 1.0 if alpha >= 0 else -1.0
            st.pending = "blocked"
            self.reversals += 1
            return p.reverse_speed_mps * np.array([np.cos(heading + np.pi + st.reverse_turn * np.pi / 4),
                                                   np.sin(heading + np.pi + st.reverse_turn * np.pi / 4)])
        cruise = st.task.cruise_speed_mps if st.usable else min(st.task.cruise_speed_mps, p.unusable_speed_mps)
        v = pursuit_velocity(st.path, st.s, pos, heading, cruise, lookahead, p.lat_accel_mps2, p.decel_mps2,
                             np.radians(p.max_course_deg), self.axle_m)
        n = float(np.hypot(*v))
        return v * min(1.0, v_gov / n) if n > 1e-12 else v


_LOG_COLUMNS = ("ego", "time_s", "trigger", "generations", "generation_usable", "usable", "clearance_m",
                "path_length_m", "known_points", "plan_ms", "best_fitness", "path")

