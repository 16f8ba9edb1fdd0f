"""The plug-ins of a scenario, chosen and parameterised one way for every kind.

``ego.controller``, ``ego.sensor``, ``ego.layers`` (a list, in order) and ``ego.actuator`` name
plug-ins registered in :data:`KINDS`; the table ``[KIND.NAME]`` (``[controllers.apf]``,
``[sensors.radar]``, ``[layers.traffic]``, ``[actuators.kinematic]``, ...) holds the parameters of
plug-in NAME of that kind. Every registered plug-in that has parameters gets its table validated,
chosen or not (defaults where the file has none): :func:`build_tables` returns them by table name
(``Scenario.tables``, ``Context.params``). Keys of the layout before (``[radar]``, ``[safety]``,
``[rules]``, ``[actuator]``, ``ego.rules``, ``ego.safety``) give one line naming the new key
(:func:`check_renamed`).
"""
from __future__ import annotations

from sumo_avoid.actuation import ACTUATORS
from sumo_avoid.control import CONTROLLERS
from sumo_avoid.core.config import ScenarioError, build
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


def check_choices(ego, file: str) -> None:
    """``ego.controller``, ``ego.sensor``, each of ``ego.layers`` and ``ego.actuator`` name registered plug-ins."""
    choices = [("ego.controller", ego.controller, CONTROLLERS), ("ego.sensor", ego.sensor, SENSORS),
               *((f"ego.layers[{i}]", name, LAYERS) for i, name in enumerate(ego.layers)),
               ("ego.actuator", ego.actuator, ACTUATORS)]
    for key, value, registry in choices:
        if value not in registry:
            raise ScenarioError(file, key, f"one of {registry.names()}", value)


def check_driven_by_sumo(spec, file: str) -> None:
    """A controller that leaves the egos to SUMO's driver (``Needs(drives=False)``, ``sumo``) needs
    egos on a route: an [arena]'s flock is spawned off the lanes, where SUMO's models cannot drive it."""
    name = spec.ego.controller
    if spec.arena is not None and not CONTROLLERS[name].factory.needs.drives:
        plugins = [n for n in CONTROLLERS.names() if CONTROLLERS[n].factory.needs.drives]
        raise ScenarioError(file, "ego.controller", f"a controller that drives the egos in an [arena] (one of {plugins}: "
                            f"'{name}' leaves them to SUMO's driver, which drives only on a route's lanes)", name)


def build_tables(spec, file: str) -> dict:
    """Every registered plug-in's validated parameters by table name ("controllers.apf", ...), from
    the scenario's ``[KIND.NAME]`` tables (``spec.controllers``, ``spec.sensors``, ...) or defaults;
    a table naming no registered plug-in with parameters is an error."""
    tables = {}
    for kind, registry in KINDS.items():
        given = getattr(spec, kind)
        for entry in registry.entries():
            if entry.params is not None:
                tables[f"{kind}.{entry.name}"] = build(entry.params, given.get(entry.name, {}), file, f"{kind}.{entry.name}")
        for name in given:
            if name not in registry or registry[name].params is None:
                named = [e.name for e in registry.entries() if e.params is not None]
                raise ScenarioError(file, f"{kind}.{name}", f"a {registry.kind} name with parameters, one of {named}", name)
    return tables
