"""One registry mechanism for every kind of plug-in: name -> (factory, parameter dataclass).

A new controller (sensor, layer, actuator, metric) is one file plus one ``register`` line in its
package's ``__init__``; a test (or a user's script) may register its own before loading a scenario.
A scenario chooses a plug-in by name and gives its parameters in the table ``[KIND.NAME]``
(``[controllers.apf]``, ``[sensors.radar]``, ``[layers.traffic]``, ``[actuators.kinematic]``),
validated against the registered dataclass (:mod:`sumo_avoid.scenario.plugins`).

Plug-ins of other packages (docs/plugins.md) are found by name, in this order: a registered
(built-in) one; an entry point of the registry's group (``sumo_avoid.controllers``,
``sumo_avoid.layers``, ``sumo_avoid.sensors``, ``sumo_avoid.metrics``, ``sumo_avoid.actuators``;
:mod:`importlib.metadata`, as pytest finds its plug-ins); an import path ``"package.module:Attr"``.
Such a plug-in is the class (or factory) itself; its parameter dataclass, if it has parameters, is
its class attribute ``Params`` (frozen). What was found is cached here, the registries being the
only mutable state; nothing is imported until a scenario names it.
"""
from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any, Callable, Iterator

BUILT_IN = "built-in"
IMPORT_PATH = "import path"


@dataclass(frozen=True)
class Entry:
    name: str
    factory: Callable[..., Any]
    params: type | None = None  # frozen dataclass of its parameters, or None
    origin: str = BUILT_IN  # "built-in", "entry point (DIST)" or "import path"

    @property
    def doc(self) -> str:
        text = (self.factory.__doc__ or "").strip()
        return text.splitlines()[0] if text else ""


class PluginNotFound(LookupError):
    """A name no plug-in answers to; ``str(err)`` says why in a few words (one line)."""


class Registry:
    def __init__(self, kind: str, group: str | None = None):
        self.kind = kind
        self.group = group or f"sumo_avoid.{kind}s"  # the entry point group of other packages' plug-ins
        self._entries: dict[str, Entry] = {}
        self._found: dict[str, Entry] = {}  # found through an entry point or an import path

    def register(self, name: str, factory: Callable[..., Any], params: type | None = None) -> Callable[..., Any]:
        if name in self._entries:
            raise ValueError(f"{self.kind} {name!r} is registered already")
        self._entries[name] = Entry(name, factory, params)
        return factory

    def unregister(self, name: str) -> None:
        self._entries.pop(name, None)

    def find(self, name: str) -> Entry:
        """The plug-in called ``name``: registered, else an entry point, else an import path; raises
        :class:`PluginNotFound` saying why."""
        if name in self._entries:
            return self._entries[name]
        if name not in self._found:
            self._found[name] = self._by_import_path(name) if ":" in name else self._by_entry_point(name)
        return self._found[name]

    def __getitem__(self, name: str) -> Entry:
        try:
            return self.find(name)
        except PluginNotFound:
            raise KeyError(name) from None

    def __contains__(self, name: object) -> bool:
        try:
            return isinstance(name, str) and self.find(name) is not None
        except PluginNotFound:
            return False

    def __iter__(self) -> Iterator[str]:
        return iter(sorted(self._entries))

    def names(self) -> list[str]:
        """The registered (built-in) names."""
        return sorted(self._entries)

    def entries(self) -> list[Entry]:
        """The registered (built-in) entries."""
        return [self._entries[n] for n in self.names()]

    def installed(self) -> list[tuple[str, str, Entry | str]]:
        """Every entry point of the group: (name, origin, its entry or why it cannot be loaded)."""
        out = []
        for ep in sorted(entry_points(group=self.group), key=lambda e: e.name):
            origin = _origin(ep)
            if ep.name in self._entries:
                out.append((ep.name, origin, f"shadowed by the {BUILT_IN} {self.kind} of that name"))
                continue
            try:
                out.append((ep.name, origin, self.find(ep.name)))
            except PluginNotFound as e:
                out.append((ep.name, origin, str(e)))
        return out

    def _by_entry_point(self, name: str) -> Entry:
        for ep in entry_points(group=self.group):
            if ep.name == name:
                try:
                    obj = ep.load()
                except Exception as e:  # whatever the package raises on import
                    raise PluginNotFound(f"entry point {ep.value!r} of {_origin(ep)} cannot be loaded: "
                                         f"{_one_line(e)}") from None
                return self._entry(name, obj, _origin(ep))
        raise PluginNotFound(f"no {self.kind} of that name, built in or an entry point of group {self.group}")

    def _by_import_path(self, name: str) -> Entry:
        return self._entry(name, import_object(name), IMPORT_PATH)

    def _entry(self, name: str, obj: Any, origin: str) -> Entry:
        if not callable(obj):
            raise PluginNotFound(f"{name} is not a {self.kind} class or function (a {type(obj).__name__})")
        params = getattr(obj, "Params", None)
        if params is not None and not (isinstance(params, type) and dataclasses.is_dataclass(params)
                                       and params.__dataclass_params__.frozen):
            raise PluginNotFound(f"{name}.Params is not a frozen dataclass")
        return Entry(name, obj, params, origin)


def is_import_path(text: str) -> bool:
    """``text`` has the form MODULE:ATTR (dotted names on both sides)."""
    module, sep, attr = text.partition(":")
    return bool(sep) and all(p.isidentifier() for p in (*module.split("."), *attr.split(".")))


def import_object(path: str) -> Any:
    """The object at import path ``"package.module:Attr"`` (``Attr`` may be dotted); raises
    :class:`PluginNotFound` saying why (one line)."""
    if not is_import_path(path):
        raise PluginNotFound("an import path is MODULE:ATTR, e.g. mypkg.control:MyController")
    module, _, attr = path.partition(":")
    try:
        obj = importlib.import_module(module)
    except Exception as e:  # ImportError, or whatever the module raises on import
        raise PluginNotFound(f"cannot import {module!r}: {_one_line(e)}") from None
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise PluginNotFound(f"AttributeError: module {module!r} has no attribute {attr!r}")
        obj = getattr(obj, part)
    return obj


def _origin(ep) -> str:
    dist = getattr(ep, "dist", None)
    return f"entry point ({dist.name})" if dist is not None else "entry point"


def _one_line(e: Exception) -> str:
    text = " ".join(str(e).split())
    return f"{type(e).__name__}: {text}" if text else type(e).__name__
