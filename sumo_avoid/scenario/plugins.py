"""The plug-ins of a scenario, chosen and parameterised one way for every kind.

``ego.controller``, ``ego.sensor``, ``ego.layers`` (a list, in order) and ``ego.actuator`` name
plug-ins registered in :data:`KINDS`; the table ``[KIND.NAME]`` (``[controllers.apf]``,
``[sensors.radar]``, ``[layers.traffic]``, ``[actuators.kinematic]``, ...) holds the parameters of
plug-in NAME of that kind. Every registered plug-in that has parameters gets its table validated,
chosen or not (defaults where the file has none): :func:`build_tables` returns them by table name
(``Scenario.tables``, ``Context.params``). Keys of the layout before (``[radar]``, ``[safety]``,
``[rules]``, ``[actuator]``, ``ego.rules``, ``ego.safety``) give one line naming the new key
(:func:`check_renamed`).

A name that is not built in may be a plug-in of another package, an entry point or an import path
``"mypkg.control:MyController"`` (:class:`~sumo_avoid.core.registry.Registry`, docs/plugins.md): its
``[KIND.NAME]`` table is validated against its ``Params`` the same way (the table name quoted in
TOML when it holds a dot or colon).
"""
from __future__ import annotations

from sumo_avoid.actuation import ACTUATORS
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import ScenarioError, build
from sumo_avoid.core.registry import Entry, PluginNotFound, Registry
from sumo_avoid.safety import LAYERS
from sumo_avoid.sensing import SENSORS

KINDS = {"controllers": CONTROLLERS, "sensors": SENSORS, "layers": LAYERS, "actuators": ACTUATORS}

# top-level tables and [ego] keys of the layout before, and what replaces them
RENAMED = {"radar": "[sensors.radar]", "safety": "[layers.danger_time]", "rules": "[layers.traffic]"}
RENAMED_EGO = {"rules": 'ego.layers (in order; "traffic" = the rules layer, [] = no layer)',
               "safety": 'ego.layers (e.g. ["traffic", "danger_time"])'}


class RenamedKey(ScenarioError):
    """A key of the layout before: ``FILE: key 'OLD' was renamed: use NEW`` (one line, exit 2)."""

    def __init__(self, file: str, key: str, new: str):
        super().__init__(file, key, f"the new key {new}", show_got=False)
        self.new = new
        ValueError.__init__(self, f"{file}: key '{key}' was renamed: use {new}")

    def __reduce__(self):  # picklable like ScenarioError, with its own message
        return RenamedKey, (self.file, self.key, self.new)


def check_renamed(data: dict, file: str) -> None:
    """Raise :class:`RenamedKey` for the first key of the layout before in the raw data (the file
    with its ``--set`` overrides applied)."""
    for key, new in RENAMED.items():
        if key in data:
            raise RenamedKey(file, key, new)
    act = data.get("actuator")
    if act is not None:
        if isinstance(act, dict) and "mode" in act:
            raise RenamedKey(file, "actuator.mode", "ego.actuator, the table's other keys in [actuators.NAME] "
                                                    "(relaxation: relax_max_accel_mps2 is max_accel_mps2)")
        raise RenamedKey(file, "actuator", "[actuators.kinematic] (the default ego.actuator; "
                                           "[actuators.relaxation] for ego.actuator = \"relaxation\")")
    ego = data.get("ego")
    for key, new in RENAMED_EGO.items():
        if isinstance(ego, dict) and key in ego:
            raise RenamedKey(file, f"ego.{key}", new)


def choose(registry: Registry, name: str, file: str, key: str) -> Entry:
    """The plug-in ``name`` of ``registry`` (built in, an entry point or an import path), or one line
    naming ``key``, what was expected and why it was not found."""
    try:
        return registry.find(name)
    except PluginNotFound as e:
        raise ScenarioError(file, key, f"one of {registry.names()}, an entry point of group {registry.group} or an "
                                       f"importable MODULE:ATTR ({e})", name) from None


def check_choices(ego, file: str) -> None:
    """``ego.controller``, ``ego.sensor``, each of ``ego.layers`` and ``ego.actuator`` name plug-ins."""
    for key, value, registry in _chosen(ego):
        choose(registry, value, file, key)


def _chosen(ego) -> list[tuple[str, str, Registry]]:
    return [("ego.controller", ego.controller, CONTROLLERS), ("ego.sensor", ego.sensor, SENSORS),
            *((f"ego.layers[{i}]", name, LAYERS) for i, name in enumerate(ego.layers)),
            ("ego.actuator", ego.actuator, ACTUATORS)]


def check_driven_by_sumo(spec, file: str) -> None:
    """A controller that leaves the egos to SUMO's driver (``Needs(drives=False)``, ``sumo``) needs
    egos on a route: an [arena]'s flock is spawned off the lanes, where SUMO's models cannot drive it."""
    name = spec.ego.controller
    if spec.arena is not None and not CONTROLLERS[name].factory.needs.drives:
        plugins = [n for n in CONTROLLERS.names() if CONTROLLERS[n].factory.needs.drives]
        raise ScenarioError(file, "ego.controller", f"a controller that drives the egos in an [arena] (one of {plugins}: "
                            f"'{name}' leaves them to SUMO's driver, which drives only on a route's lanes)", name)


def build_tables(spec, file: str) -> dict:
    """Every built-in plug-in's validated parameters by table name ("controllers.apf", ...), and those
    of the chosen plug-ins of other packages, from the scenario's ``[KIND.NAME]`` tables
    (``spec.controllers``, ``spec.sensors``, ...) or defaults; a table naming no plug-in with
    parameters is an error."""
    tables = {}
    chosen = _chosen(spec.ego)
    for kind, registry in KINDS.items():
        given = getattr(spec, kind)
        entries = registry.entries() + [registry.find(name) for _, name, reg in chosen
                                        if reg is registry and name not in registry.names()]
        why = {}
        for name in given:
            try:
                entry = registry.find(name)
            except PluginNotFound as e:
                why[name] = f" ({e})"
                continue
            if entry not in entries:
                entries.append(entry)
        for entry in entries:
            if entry.params is not None:
                tables[f"{kind}.{entry.name}"] = build(entry.params, given.get(entry.name, {}), file, f"{kind}.{entry.name}")
        with_params = {e.name for e in entries if e.params is not None}
        for name in given:
            if name not in with_params:
                named = [e.name for e in registry.entries() if e.params is not None]
                raise ScenarioError(file, f"{kind}.{name}", f"a {registry.kind} name with parameters, one of {named}"
                                                                 f"{why.get(name, '')}", name)
    return tables
