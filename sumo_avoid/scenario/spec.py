"""Scenario files: TOML + SUMO XML, validated on load into frozen dataclasses.

A scenario names a SUMO network, SUMO route files (vehicle types, vehicles, flows), which of
those vehicles the plug-in drives (the egos), their plug-ins -- controller, sensor, layers,
actuator -- and their parameters (``[KIND.NAME]`` tables, :mod:`sumo_avoid.scenario.plugins`) and
the output options. ``docs/scenario_format.md`` lists every key (generated from the
dataclasses below by ``python -m sumo_avoid.scenario.key_reference``).
"""
from __future__ import annotations

import pathlib
import re
import sys
from dataclasses import dataclass, replace

import numpy as np

from sumo_avoid.core.config import FieldError, ScenarioError, build, field_doc
from sumo_avoid.metrics import METRICS
from sumo_avoid.scenario.checks import (
    DEFINED,
    SAME_KIND,
    check_arena,
    check_ego_ids,
    check_ego_keys,
    check_goals,
    check_sumo_inputs,
    elements,
    is_convex,
)
from sumo_avoid.scenario import sumocfg
from sumo_avoid.scenario.obstacles import RandomObstaclesConfig, draw
from sumo_avoid.scenario.plugins import build_tables, check_choices, check_driven_by_sumo, check_renamed, choose
from sumo_avoid.sumo.inputs import FLOCK_MAX_SPEED_MPS, refused_file

MIN_STEP_S, MAX_STEP_S = 0.001, 10.0  # SUMO counts time in ms
MAX_DURATION_S = 86_400.0  # one simulated day: a longer run is a typo, not a study
MAX_BEGIN_S = 365 * 86_400.0  # a year of simulated time
MAX_SEED = 2**31 - 1
# absurd magnitudes are typos (1e300 overflowed the arena's geometry mid-run): the bounds of an arena
MAX_ARENA_M = 1e6  # an arena's side, m
MAX_COORD_M = 1e7  # a coordinate of an arena's corner or start, m
MAX_VEHICLE_M = 100.0  # a flock vehicle's length or width, m

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass(frozen=True)
class SimConfig:
    net: str = field_doc(doc="SUMO network file (.net.xml), relative to the scenario file")
    sumocfg: str = field_doc("", doc="SUMO configuration (.sumocfg), relative to the scenario file: its net, route and "
                                     "additional files, step length, begin/end, seed and other options fill the [sim] "
                                     "keys not given here (SUMO configurations, above)")
    routes: tuple[str, ...] = field_doc((), doc="SUMO route files (types, vehicles, flows), relative paths")
    additional: tuple[str, ...] = field_doc((), doc="SUMO additional files (polygons, detectors), relative paths")
    step_s: float = field_doc(0.1, doc="simulation step, s")
    duration_s: float = field_doc(120.0, doc="time limit of the run, s")
    begin_s: float = field_doc(0.0, doc="simulation time the run starts at (SUMO's --begin), s")
    seed: int = field_doc(1, doc="seed for SUMO and for the plug-in's random numbers")
    lateral_resolution_m: float = field_doc(0.8, doc="SUMO sublane width, m (sublane model on)")
    sumo_collisions: bool = field_doc(True, doc="SUMO's own collision check and output beside the plug-in's "
                                                "footprint check (always on); off saves SUMO's pairwise per-lane "
                                                "check (always off in an [arena])")
    options: dict = field_doc(default_factory=dict, doc="[sim.options] table: more SUMO options by SUMO's names, e.g. "
                                                        "\"pedestrian.striping.reserve-oncoming\" = 0.34 (not those a "
                                                        "[sim] key sets or the plug-in owns)")

    def __post_init__(self):
        if not MIN_STEP_S <= self.step_s <= MAX_STEP_S or abs(self.step_s * 1000 - round(self.step_s * 1000)) > 1e-6:
            raise FieldError("step_s", f"a step in [{MIN_STEP_S}, {MAX_STEP_S}] s, a whole number of ms (SUMO's time "
                                       "resolution)", self.step_s)
        if not 0 <= self.begin_s <= MAX_BEGIN_S:
            raise FieldError("begin_s", f"a time in [0, {MAX_BEGIN_S:g}] s", self.begin_s)
        if not 0 < self.duration_s <= MAX_DURATION_S:
            raise FieldError("duration_s", f"a duration in (0, {MAX_DURATION_S:g}] s", self.duration_s)
        if self.step_s > self.duration_s:
            raise FieldError("step_s", f"a step no longer than sim.duration_s ({self.duration_s} s)", self.step_s)
        if not 0 <= self.seed <= MAX_SEED:
            raise FieldError("seed", f"an integer in [0, {MAX_SEED}] (SUMO's seed is a 32-bit integer)", self.seed)
        if self.lateral_resolution_m <= 0:
            raise FieldError("lateral_resolution_m", "a positive width, m", self.lateral_resolution_m)


@dataclass(frozen=True)
class EgoConfig:
    ids: tuple[str, ...] = field_doc((), doc="ids of vehicles in the route files that the plug-in drives "
                                             "(may be empty when an [arena] spawns the egos)")
    controller: str = field_doc("apf_sa", doc="controller name (see `sumo-avoid controllers`; [controllers.NAME] table); "
                                              "'sumo': SUMO's own driver, the baseline (no table; see above)")
    sensor: str = field_doc("truth", doc="what controllers see: 'truth' (ground truth) or 'radar' ([sensors.radar] "
                                         "table, also the parameters of the radar 'truth' carries for a layer "
                                         "that needs scans)")
    layers: tuple[str, ...] = field_doc(("traffic",), doc="layers between controller and actuator, in this order: "
                                                          "'traffic' (signals, right of way, road speed; "
                                                          "[layers.traffic]), 'danger_time' (radar danger-time "
                                                          "braking; [layers.danger_time]); [] = none (a study of "
                                                          "rule-free controllers). With ego.sensor = 'radar', "
                                                          "danger_time runs as a monitor (counters only) when "
                                                          "not listed")
    actuator: str = field_doc("kinematic", doc="'kinematic' (car: accel/yaw limits; [actuators.kinematic]) or "
                                               "'relaxation' (flocking reference: dv/dt = (v_des - v)/tau; "
                                               "[actuators.relaxation])")
    cruise_speed_mps: float = field_doc(20.0, doc="desired cruising speed, m/s")
    goal: tuple[float, ...] | str | None = field_doc(
        None, signed=True, doc="goal of every ego: [x, y] in net coordinates, m, or an edge id (the goal is where "
                               "the ego's route path leaves that edge, the first time if it passes twice); "
                               "default: end of each ego's route")
    goals: dict[str, tuple[float, ...] | str] = field_doc(
        default_factory=dict, signed=True, doc="[ego.goals] table, a goal per ego: EGO_ID = [x, y] or \"EDGE_ID\" "
                                               "(as ego.goal; quote ids with dots); egos not in it take ego.goal")
    goal_tolerance_m: float = field_doc(5.0, doc="the goal is reached when an ego centre comes this close, m")

    def __post_init__(self):
        dup = _first_duplicate(self.layers)
        if dup is not None:
            raise FieldError(f"layers[{dup}]", "layer names listed once (this one is listed before)", self.layers[dup])
        for key, goal in (("goal", self.goal), *((f"goals.{v}", g) for v, g in self.goals.items())):
            if isinstance(goal, tuple) and len(goal) != 2:
                raise FieldError(key, "[x, y] or an edge id", list(goal))
            if goal == "":
                raise FieldError(key, "[x, y] or a non-empty edge id", goal)


@dataclass(frozen=True)
class ArenaConfig:
    size_m: float = field_doc(250.0, doc="side of the square arena (virtual walls), m")
    origin: tuple[float, ...] = field_doc((0.0, 0.0), signed=True, doc="lower-left corner [x, y] of the arena, m")
    n_agents: int = field_doc(100, doc="number of flocking vehicles spawned at random inside the arena (0: only the "
                                       "walls; the egos come from ego.ids, e.g. a field for a path planner)")
    min_spacing_m: float = field_doc(6.0, doc="smallest distance between two start positions, m")
    margin_m: float = field_doc(5.0, doc="start positions keep this far from walls and obstacles, m")
    initial_speed_mps: float = field_doc(0.0, doc="initial speed (random heading), m/s")
    length_m: float = field_doc(4.0, positive=True, doc="vehicle length, m")
    width_m: float = field_doc(1.8, positive=True, doc="vehicle width, m")
    id_prefix: str = field_doc("f", doc="vehicle ids are PREFIX0 .. PREFIX(N-1)")
    starts: tuple[tuple[float, ...], ...] = field_doc((), signed=True, doc="[[x, y], ...] fixed start centres, one "
                                                                           "per agent, m (default: random)")
    start_heading_deg: float = field_doc(0.0, signed=True, doc="with starts: every agent's initial heading, deg CCW "
                                                               "from +x")

    def __post_init__(self):
        if len(self.origin) != 2:
            raise ValueError("arena.origin = [x, y]")
        if not 0 < self.size_m <= MAX_ARENA_M:  # 1e300 overflowed numpy mid-run
            raise FieldError("size_m", f"a side in (0, {MAX_ARENA_M:g}] m", self.size_m)
        for key, v in (("origin", max(map(abs, self.origin))), *(("starts", abs(c)) for p in self.starts for c in p)):
            if v > MAX_COORD_M:
                raise FieldError(key, f"coordinates within ±{MAX_COORD_M:g} m", v)
        for key, v in (("length_m", self.length_m), ("width_m", self.width_m)):
            if v > MAX_VEHICLE_M:
                raise FieldError(key, f"a vehicle size of at most {MAX_VEHICLE_M:g} m", v)
        if not 0 <= self.initial_speed_mps <= FLOCK_MAX_SPEED_MPS:
            raise FieldError("initial_speed_mps", f"a speed in [0, {FLOCK_MAX_SPEED_MPS:g}] m/s (the flock's "
                                                  "vehicle type's top speed)", self.initial_speed_mps)
        if self.starts and (len(self.starts) != self.n_agents or any(len(p) != 2 for p in self.starts)):
            raise FieldError("starts", f"{self.n_agents} points [x, y] (one per agent)", [list(p) for p in self.starts])

    @property
    def ids(self) -> tuple[str, ...]:
        return tuple(f"{self.id_prefix}{k}" for k in range(self.n_agents))


@dataclass(frozen=True)
class ObstacleConfig:
    id: str = field_doc(doc="obstacle id (also its SUMO polygon id)")
    shape: tuple[tuple[float, ...], ...] = field_doc(signed=True, doc="convex polygon [[x, y], ...] in net coordinates, m")

    def __post_init__(self):
        if len(self.shape) < 3 or any(len(p) != 2 for p in self.shape):
            raise FieldError("shape", ">= 3 points [x, y]", [list(p) for p in self.shape])
        if not is_convex(self.polygon):
            raise FieldError("shape", "a convex polygon with a non-zero area (corners in order, no three on a line)",
                             [list(p) for p in self.shape])

    @property
    def polygon(self) -> np.ndarray:
        """(k, 2) vertices, m."""
        return np.asarray(self.shape, float)


@dataclass(frozen=True)
class OutputConfig:
    record_radius_m: float = field_doc(300.0, doc="record non-ego vehicles within this distance of an ego, m (0 = all)")
    plots: bool = field_doc(True, doc="write trajectory.png and timeseries.png")
    metrics: tuple[str, ...] = field_doc((), doc="metrics to compute beside the standard set and the controller's own (flocking: "
                                                 "order parameters and fitness), by name: run, collisions, min_gap, phi_coll, "
                                                 "phi_wall, plugin_stats, motion, flocking")


@dataclass(frozen=True)
class ScenarioSpec:
    name: str = field_doc(doc="scenario name")
    sim: SimConfig = field_doc(doc="[sim] table")
    ego: EgoConfig = field_doc(doc="[ego] table")
    description: str = field_doc("", doc="free text")
    output: OutputConfig = field_doc(OutputConfig(), doc="[output] table")
    controllers: dict = field_doc(default_factory=dict, doc="[controllers.NAME] tables: parameters of controller NAME")
    sensors: dict = field_doc(default_factory=dict, doc="[sensors.NAME] tables: parameters of sensor NAME")
    layers: dict = field_doc(default_factory=dict, doc="[layers.NAME] tables: parameters of layer NAME")
    actuators: dict = field_doc(default_factory=dict, doc="[actuators.NAME] tables: parameters of actuator NAME")
    arena: ArenaConfig | None = field_doc(None, doc="[arena] table: spawn a flock in a square arena (flocking)")
    obstacles: tuple[ObstacleConfig, ...] = field_doc((), doc="[[obstacles]] static convex polygons (id, shape)")
    random_obstacles: RandomObstaclesConfig | None = field_doc(
        None, doc="[random_obstacles] table: static obstacles drawn from the seed, added to [[obstacles]]")
    tune: dict = field_doc(default_factory=dict, doc="[tune.NAME] tables: search bounds of `sumo-avoid tune NAME` "
                                                     "(flocking: KEY = [LO, HI] per [controllers.flocking] key)")

    def __post_init__(self):
        if not self.ego.ids and (self.arena is None or self.arena.n_agents == 0):
            raise FieldError("ego.ids", "at least one ego id (or an [arena] table with n_agents > 0)", [])
        for key, ids in (("ego.ids", self.ego.ids), ("obstacles", [o.id for o in self.obstacles])):
            dup = _first_duplicate(ids)
            if dup is not None:
                raise FieldError(f"{key}[{dup}]" + (".id" if key == "obstacles" else ""),
                                 "ids used once (this one is used before)", ids[dup])


def _first_duplicate(ids) -> int | None:
    seen = set()
    for i, v in enumerate(ids):
        if v in seen:
            return i
        seen.add(v)
    return None


@dataclass(frozen=True)
class Scenario:
    """A validated scenario with absolute paths and the validated parameters of every plug-in."""

    spec: ScenarioSpec
    path: pathlib.Path
    net_file: pathlib.Path
    route_files: tuple[pathlib.Path, ...]
    additional_files: tuple[pathlib.Path, ...]
    tables: dict  # "KIND.NAME" -> frozen params dataclass, for every registered plug-in with parameters
    sumocfg: sumocfg.SumoConfig | None = None  # the SUMO configuration sim.sumocfg names (or the scenario itself)
    sumo_options: tuple[tuple[str, str], ...] = ()  # sim.options for SUMO's command line (canonical names)

    @property
    def name(self) -> str:
        return self.spec.name

    def table(self, name: str):
        """The validated parameters of table ``name`` ("layers.traffic", "actuators.kinematic", ...),
        chosen or not (the rule metrics judge by ``[layers.traffic]`` also in runs without the layer)."""
        return self.tables[name]

    @property
    def controller_params(self) -> dict:
        """Controller name -> its parameters, for every registered controller."""
        return {k.split(".", 1)[1]: v for k, v in self.tables.items() if k.startswith("controllers.")}

    @property
    def params(self):
        """The chosen controller's parameters."""
        return self.tables[f"controllers.{self.spec.ego.controller}"]


def parse_override(text: str, file: str) -> tuple[list[str], object]:
    """``KEY=VALUE`` -> (dotted path, value). VALUE is read as TOML, else taken as a string."""
    if "=" not in text:
        raise ScenarioError(file, text, "KEY=VALUE in --set", show_got=False)
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise ScenarioError(file, key or text, "a dotted key like sim.seed in --set", show_got=False)
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key.split("."), value


def apply_overrides(data: dict, overrides: list[str], file: str) -> dict:
    data = _deepcopy(data)
    for text in overrides:
        path, value = parse_override(text, file)
        node = data
        for part in path[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise ScenarioError(file, ".".join(path), "a key inside a table", show_got=False)
        node[path[-1]] = value
    return data


def _deepcopy(d):
    return {k: _deepcopy(v) if isinstance(v, dict) else v for k, v in d.items()}


def read_toml(path: pathlib.Path) -> dict:
    file = str(path)
    if not path.is_file():
        raise ScenarioError(file, "<file>", "an existing scenario file", show_got=False)
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(file, "<syntax>", f"valid TOML ({e})", show_got=False) from None
    except UnicodeDecodeError as e:
        raise ScenarioError(file, "<syntax>", f"a UTF-8 text file (TOML), not binary ({e.reason} at byte "
                            f"{e.start})", show_got=False) from None
    except OSError as e:
        raise ScenarioError(file, "<file>", f"a readable file ({e.strerror})", show_got=False) from None


def load(path, overrides: list[str] = (), controller: str | None = None, seed: int | None = None) -> Scenario:
    """Read, override and validate a scenario file (TOML, or a SUMO configuration ``.sumocfg`` whose
    egos come from the overrides, ``ego.ids``). Raises :class:`ScenarioError`."""
    path = pathlib.Path(path)
    file = str(path)
    if sumocfg.is_sumocfg(path):
        if not path.is_file():
            raise ScenarioError(file, "<file>", "an existing SUMO configuration file", show_got=False)
        raw = {"name": path.stem, "sim": {"sumocfg": path.name}}
    else:
        raw = read_toml(path)
    data = apply_overrides(raw, list(overrides), file)
    if controller is not None:
        data.setdefault("ego", {})["controller"] = controller
    if seed is not None:
        data.setdefault("sim", {})["seed"] = seed
    if sumocfg.is_sumocfg(path) and not (data.get("ego") or {}).get("ids"):
        raise ScenarioError(file, "--ego", "the id of a vehicle of the configuration's route files for the plug-in "
                                           "to drive (--ego ID, repeatable)", show_got=False)
    base = path.resolve().parent
    data, cfg = sumocfg.merge(data, base, file)
    check_renamed(data, file)
    spec = sumocfg.checked(cfg, build, ScenarioSpec, data, file)  # a value a SUMO configuration gave: its option
    if spec.random_obstacles is not None:
        spec = _with_random_obstacles(spec, file)
    check_choices(spec.ego, file)
    check_driven_by_sumo(spec, file)
    for i, m in enumerate(spec.output.metrics):
        choose(METRICS, m, file, f"output.metrics[{i}]")
    tables = build_tables(spec, file)
    options = sumocfg.sumo_options(spec.sim.options, base, file)

    def existing(rel: str, key: str, what: str) -> pathlib.Path:
        p = (base / rel).resolve()
        if not p.is_file():
            raise ScenarioError(file, key, f"an existing {what} file", rel)
        return p

    net = existing(spec.sim.net, "sim.net", "SUMO network")
    routes = tuple(existing(r, f"sim.routes[{i}]", "SUMO route") for i, r in enumerate(spec.sim.routes))
    adds = tuple(existing(r, f"sim.additional[{i}]", "SUMO additional") for i, r in enumerate(spec.sim.additional))
    sumocfg.checked(cfg, check_sumo_inputs, spec, net, routes, adds, file)
    sumocfg.checked(cfg, check_ego_ids, spec, routes + adds, file)
    check_goals(spec, net, file)
    scn = Scenario(spec, path, net, routes, adds, tables, cfg, options)
    check_ego_keys(spec, scn.controller_params, file)
    if spec.arena is not None:
        check_arena(spec, file)
    return scn


def _with_random_obstacles(spec: ScenarioSpec, file: str) -> ScenarioSpec:
    """The spec with the seed's random obstacles appended to ``obstacles`` (scenario/obstacles.py)."""
    cfg = spec.random_obstacles
    try:
        polys = draw(cfg, spec.sim.seed)
    except ValueError as e:
        raise ScenarioError(file, "random_obstacles.count", f"obstacles that fit the region ({e})", cfg.count) from None
    drawn = tuple(ObstacleConfig(f"{cfg.id_prefix}{k}", tuple(map(tuple, pg.tolist()))) for k, pg in enumerate(polys))
    return replace(spec, obstacles=spec.obstacles + drawn)


def sumo_load_error(scn: Scenario, message: str, at_start: bool = False) -> ScenarioError:
    """SUMO's refusal to load the scenario's files as one line naming the file: when SUMO's message
    names a trip, vehicle, flow or route (e.g. "The edge 'x' within the route for trip 't' is not
    known"), the route or additional file that defines it (key ``sim.routes[i]``); ``at_start`` (SUMO
    would not start), else the file SUMO's program refuses (:func:`~sumo_avoid.sumo.inputs.refused_file`);
    else key ``sim``."""
    sumo = " ".join(message.split())
    keyed = [(f"sim.routes[{i}]", f) for i, f in enumerate(scn.route_files)]
    keyed += [(f"sim.additional[{i}]", f) for i, f in enumerate(scn.additional_files)]
    for tag, eid in re.findall(r"\b(" + "|".join(DEFINED) + r") '([^']*)'", sumo):
        kinds = SAME_KIND.get(tag, (tag,))  # SUMO calls a <trip> a vehicle once it is inserted
        for key, f in keyed:
            if any((k, eid) in elements(f) for k in kinds):
                return ScenarioError(str(scn.path), key, f"a file SUMO can load: {f}, {tag} '{eid}' (SUMO: {sumo})",
                                     show_got=False)
    refused = refused_file(scn.net_file, scn.additional_files, scn.route_files) if at_start else None
    for key, f in keyed:
        if f == refused:
            return ScenarioError(str(scn.path), key, f"a file SUMO can load: {f} (SUMO: {sumo})", show_got=False)
    return ScenarioError(str(scn.path), "sim", f"files SUMO can load (SUMO: {sumo})", show_got=False)


def with_spec(scn: Scenario, **changes) -> Scenario:
    return replace(scn, spec=replace(scn.spec, **changes))
