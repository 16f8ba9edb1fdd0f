"""One registry mechanism for every kind of plug-in: name -> (factory, parameter dataclass).

A new controller (sensor, layer, actuator, metric) is one file plus one ``register`` line in its
package's ``__init__``; a test (or a user's script) may register its own before loading a scenario.
A scenario chooses a plug-in by name and gives its parameters in the table ``[KIND.NAME]``
(``[controllers.apf]``, ``[sensors.radar]``, ``[layers.traffic]``, ``[actuators.kinematic]``),
validated against the registered dataclass (:mod:`sumo_avoid.scenario.plugins`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterator


@dataclass(frozen=True)
class Entry:
    name: str
    factory: Callable[..., Any]
    params: type | None = None  # frozen dataclass of its parameters, or None

    @property
    def doc(self) -> str:
        text = (self.factory.__doc__ or "").strip()
        return text.splitlines()[0] if text else ""


class Registry:
    def __init__(self, kind: str):
        self.kind = kind
        self._entries: dict[str, Entry] = {}

    def register(self, name: str, factory: Callable[..., Any], params: type | None = None) -> Callable[..., Any]:
        if name in self._entries:
            raise ValueError(f"{self.kind} {name!r} is registered already")
        self._entries[name] = Entry(name, factory, params)
        return factory

    def unregister(self, name: str) -> None:
        self._entries.pop(name, None)

    def __getitem__(self, name: str) -> Entry:
        return self._entries[name]

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(sorted(self._entries))

    def names(self) -> list[str]:
        return sorted(self._entries)

    def entries(self) -> list[Entry]:
        return [self._entries[n] for n in self.names()]
