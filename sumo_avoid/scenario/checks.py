"""Checks of a scenario after its keys and types (spec.py): what needs its files or the other
tables — the SUMO inputs loaded up front (sumo/inputs.py), ego ids defined and departing within the
run, goals on the net, parameters keyed by ego, the flock fitting its arena, convex obstacles. Each
raises :class:`ScenarioError` naming the scenario file and the key."""
from __future__ import annotations

import functools
import math
import pathlib
import xml.etree.ElementTree as ET

import numpy as np

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.core.interfaces import Context
from sumo_avoid.road.walls import random_positions, square
from sumo_avoid.sumo.inputs import InputError, check_inputs, depart_times, open_xml
from sumo_avoid.road.network import Road


def is_convex(pts: np.ndarray, eps: float = 1e-9) -> bool:
    """A simple convex polygon of non-zero area: every corner turns the same way (strictly) and the
    corners go round once (the turns add up to one full circle, not a star)."""
    d = np.roll(pts, -1, axis=0) - pts  # edge vectors
    nxt = np.roll(d, -1, axis=0)
    cross = d[:, 0] * nxt[:, 1] - d[:, 1] * nxt[:, 0]
    scale = max(float(np.abs(d).max()), eps) ** 2
    if not (np.all(cross > eps * scale) or np.all(cross < -eps * scale)):
        return False
    turns = np.arctan2(cross, (d * nxt).sum(axis=1))
    return bool(abs(abs(turns.sum()) - 2 * np.pi) < 1e-6)



def check_sumo_inputs(spec, net, routes, adds, file: str) -> None:
    """The net, route and additional files as SUMO would load them (sumo/inputs.py), before SUMO starts."""
    keys = {str(net): "sim.net", **{str(f): f"sim.routes[{i}]" for i, f in enumerate(routes)},
            **{str(f): f"sim.additional[{i}]" for i, f in enumerate(adds)}}
    try:
        check_inputs(net, (*adds, *routes))  # SUMO loads additional files first
    except InputError as e:
        what = f", {e.element}" if e.element else ""
        raise ScenarioError(file, keys.get(e.path, "sim"), f"a file SUMO can load: {e.path}{what}: {e.reason}",
                            show_got=False) from None


def check_ego_keys(spec, params: dict, file: str) -> None:
    """Controller parameters keyed by ego id (scripted ``stop_after_m``) name egos."""
    egos = set(spec.ego.ids) | set(spec.arena.ids if spec.arena is not None else ())
    for vid in getattr(params.get("scripted"), "stop_after_m", {}):
        if vid not in egos:
            raise ScenarioError(file, f"controllers.scripted.stop_after_m.{vid}", f"an ego id (ego.ids: "
                                f"{list(spec.ego.ids)})", vid, show_got=False)


def check_arena(spec, file: str) -> None:
    """The flock's random start positions fit the arena (drawn as the run will draw them)."""
    a = spec.arena
    if a.starts or a.n_agents == 0:
        return
    walls = square(a.origin, a.size_m)
    try:
        random_positions(Context(spec.sim.seed, spec.sim.step_s, None, walls, ()).rng(1), a.n_agents, walls,
                         tuple(o.polygon for o in spec.obstacles), min_spacing_m=a.min_spacing_m, margin_m=a.margin_m)
    except ValueError as e:
        raise ScenarioError(file, "arena.n_agents", f"a flock that fits the arena ({e})", a.n_agents) from None


def check_goals(spec, net: pathlib.Path, file: str) -> None:
    """Per-ego goals name egos; a point goal lies on the drivable area; an edge goal is a normal
    edge of the net (whether it is on the ego's route is known when SUMO has routed the ego)."""
    egos = (*spec.ego.ids, *(spec.arena.ids if spec.arena is not None else ()))
    for vid in spec.ego.goals:
        if vid not in egos:
            raise ScenarioError(file, f"ego.goals.{vid}", f"an ego id (ego.ids: {list(spec.ego.ids)})", vid,
                                show_got=False)
    goals = [("ego.goal", spec.ego.goal)] + [(f"ego.goals.{v}", g) for v, g in spec.ego.goals.items()]
    for key, goal in goals:
        if isinstance(goal, str):
            st = net.stat()
            if goal not in edges_in(str(net), st.st_mtime_ns, st.st_size):
                raise ScenarioError(file, key, f"an edge id of the network {spec.sim.net}", goal)
        elif goal is not None and spec.arena is not None:  # an open field: the goal lies inside the walls
            (x0, y0), size = spec.arena.origin, spec.arena.size_m
            if not (x0 <= goal[0] <= x0 + size and y0 <= goal[1] <= y0 + size):
                raise ScenarioError(file, key, f"a point inside the arena [{x0}, {x0 + size}] x [{y0}, {y0 + size}]",
                                    list(goal))
        elif goal is not None:
            try:
                road = Road.from_net_file(net)
            except Exception as e:  # sumolib raises many kinds
                raise ScenarioError(file, "sim.net", f"a readable SUMO network ({type(e).__name__})",
                                    spec.sim.net) from None
            x_lo, y_lo, x_hi, y_hi = road.area.bounds  # far off the net: no distance to compute (GEOS
            # overflows to inf on coordinates like 1e308 and warns on the terminal)
            far = not (x_lo - 1e3 <= goal[0] <= x_hi + 1e3 and y_lo - 1e3 <= goal[1] <= y_hi + 1e3)
            off = math.inf if far else float(road.outside_distance([goal])[0])
            if not math.isfinite(off) or off > 0.5:
                where = "over 1 km outside the net's bounds" if far else f"{off:.1f} m off it"
                raise ScenarioError(file, key, f"a point on the network's drivable area ({where})",
                                    list(goal))


@functools.lru_cache(maxsize=16)
def edges_in(path: str, mtime_ns: int, size: int) -> frozenset[str]:
    """Ids of the normal (not internal) edges of a SUMO network, parsed once per version."""
    out = set()
    try:
        with open_xml(path) as f:
            for _, el in ET.iterparse(f):
                kind = el.attrib.get("function", "normal")
                if el.tag == "edge" and "id" in el.attrib and kind not in ("internal", "crossing", "walkingarea"):
                    out.add(el.attrib["id"])
                el.clear()
    except (ET.ParseError, OSError, EOFError):
        pass
    return frozenset(out)


DEFINED = ("vehicle", "trip", "flow", "route", "person", "container")
SAME_KIND = {"vehicle": ("vehicle", "trip"), "trip": ("trip", "vehicle")}


@functools.lru_cache(maxsize=64)
def elements_in(path: str, mtime_ns: int, size: int) -> frozenset[tuple[str, str]]:
    """(tag, id) of the vehicles, trips, flows and routes of one SUMO route/additional file, parsed
    once per version (a batch loads the same scenario for every seed); a file that is not XML is
    left for SUMO to reject (with its own reason) when the run starts."""
    out = set()
    try:
        for _, el in ET.iterparse(path):
            if el.tag in DEFINED and "id" in el.attrib:
                out.add((el.tag, el.attrib["id"]))
            el.clear()
    except (ET.ParseError, OSError):
        pass
    return frozenset(out)


def elements(f) -> frozenset[tuple[str, str]]:
    st = pathlib.Path(f).stat()
    return elements_in(str(f), st.st_mtime_ns, st.st_size)


def defined_vehicles(files) -> tuple[set[str], set[str]]:
    """(vehicle and trip ids, flow ids) of the files."""
    ids, flows = set(), set()
    for f in files:
        els = elements(f)
        ids |= {vid for tag, vid in els if tag in ("vehicle", "trip")}
        flows |= {vid for tag, vid in els if tag == "flow"}
    return ids, flows


def check_ego_ids(spec, files, file: str) -> None:
    """Every ego id is a vehicle or trip of the route files (or a vehicle of a flow, FLOW.N) that
    departs within the run (as far as its depart time says)."""
    if not spec.ego.ids:
        return
    ids, flows = defined_vehicles(files)
    departs = depart_times(files)
    for i, vid in enumerate(spec.ego.ids):
        if vid not in ids and vid.rpartition(".")[0] not in flows:
            raise ScenarioError(file, f"ego.ids[{i}]", "the id of a <vehicle> or <trip> in the route files", vid)
        begin, end = spec.sim.begin_s, spec.sim.begin_s + spec.sim.duration_s
        if departs.get(vid, begin) >= end:
            ends = (f"sim.duration_s = {spec.sim.duration_s:g} s" if not begin else
                    f"t={end:g} s (sim.begin_s {begin:g} s + sim.duration_s {spec.sim.duration_s:g} s)")
            raise ScenarioError(file, f"ego.ids[{i}]", f"egos that depart within the run: '{vid}' departs at "
                                f"t={departs[vid]:g} s, the run ends at {ends}", show_got=False)
        if departs.get(vid, begin) < begin:
            raise ScenarioError(file, f"ego.ids[{i}]", f"egos that depart within the run: '{vid}' departs at "
                                f"t={departs[vid]:g} s, before the run begins at sim.begin_s = {begin:g} s (SUMO "
                                "drops it)", show_got=False)
