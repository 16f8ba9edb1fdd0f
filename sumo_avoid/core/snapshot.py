"""The immutable view of the world that everything downstream of :mod:`sumo_avoid.sumo.sim` sees.

Conventions (SPEC preamble): metres, seconds, SUMO network coordinates (x east, y north).
Positions are vehicle *centres*; headings are math angles in radians, counter-clockwise from +x.
SUMO's front-bumper position and compass angle are converted once, in :mod:`sumo_avoid.sumo.sim`.
"""
from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from sumo_avoid.core.levels import apart_mask, has_levels, same_level


def _frozen(a, dtype=float) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True)
class Snapshot:
    """All road users in the simulation at one instant (N rows, same order in every array): the
    vehicles, then the persons outside vehicles (pedestrians; riders and passengers while they walk or
    wait), each with its SUMO vehicle class (``"pedestrian"`` for a person, ``"bicycle"`` for a
    cyclist, ...). Persons are rows like vehicles (their length and width are SUMO's person type's),
    so every consumer sees them; ``is_person`` tells them apart."""

    time_s: float
    ids: tuple[str, ...]
    pos: np.ndarray  # (N, 2) centre position, m
    vel: np.ndarray  # (N, 2) velocity, m/s
    heading: np.ndarray  # (N,) rad, CCW from +x
    length: np.ndarray  # (N,) m
    width: np.ndarray  # (N,) m
    is_ego: np.ndarray  # (N,) bool, vehicles driven by the plug-in
    index: dict = field(default_factory=dict, compare=False, repr=False)  # id -> row
    signals: Mapping[str, str] = field(default_factory=dict)  # traffic light id -> state string ('rGyG...')
    lane: tuple[str, ...] = ()  # (N,) SUMO lane id each vehicle is on ("" = none / not known)
    lane_pos: np.ndarray | None = None  # (N,) SUMO position of the front bumper along that lane, m (nan = not known)
    vclass: tuple[str, ...] = ()  # (N,) SUMO vehicle class ("passenger", "bicycle", "bus", "pedestrian", ...; "" = not known)
    is_person: np.ndarray | None = None  # (N,) bool, a person (not a vehicle); default none is
    z: np.ndarray | None = None  # (N,) height of the position SUMO reports, m (core.levels; default 0)
    #: edge -> the edges crossing it without a junction (road.grade: two levels whatever the heights; default none)
    apart: Mapping[str, frozenset] = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        n = len(self.ids)
        object.__setattr__(self, "pos", _frozen(self.pos).reshape(n, 2))
        object.__setattr__(self, "vel", _frozen(self.vel).reshape(n, 2))
        for name in ("heading", "length", "width"):
            object.__setattr__(self, name, _frozen(getattr(self, name)).reshape(n))
        object.__setattr__(self, "is_ego", _frozen(self.is_ego, bool).reshape(n))
        object.__setattr__(self, "ids", tuple(self.ids))
        object.__setattr__(self, "index", {vid: i for i, vid in enumerate(self.ids)})
        object.__setattr__(self, "signals", MappingProxyType(dict(self.signals)))
        object.__setattr__(self, "lane", tuple(self.lane) if len(self.lane) == n else ("",) * n)
        lane_pos = np.full(n, np.nan) if self.lane_pos is None or len(self.lane_pos) != n else self.lane_pos
        object.__setattr__(self, "lane_pos", _frozen(lane_pos).reshape(n))
        object.__setattr__(self, "vclass", tuple(self.vclass) if len(self.vclass) == n else ("",) * n)
        person = np.zeros(n, bool) if self.is_person is None or len(self.is_person) != n else self.is_person
        object.__setattr__(self, "is_person", _frozen(person, bool).reshape(n))
        z = np.zeros(n) if self.z is None or len(self.z) != n else self.z
        object.__setattr__(self, "z", _frozen(z).reshape(n))
        object.__setattr__(self, "_levels", has_levels(self.z) or bool(self.apart))

    @property
    def n(self) -> int:
        return len(self.ids)

    @property
    def levels(self) -> bool:
        """Whether the road users stand on more than one level (a bridge over a road, core.levels)."""
        return self._levels

    def same_level(self, row: int, rows=None) -> np.ndarray:
        """Which rows (all, or ``rows``) share row ``row``'s level (core.levels: their heights; road.grade: not on an edge
        crossing row's without a junction); all on a flat net without such crossings."""
        rows = np.arange(self.n) if rows is None else np.asarray(rows, int)
        if not self._levels:
            return np.ones(len(rows), bool)
        return same_level(self.z[rows], self.z[row]) & ~apart_mask(self.apart, self.lane[row], [self.lane[r] for r in rows])

    def with_velocities(self, vel) -> Snapshot:
        """This snapshot with velocities ``vel`` (N, 2) (those the relaxation actuator holds); every other
        field is shared, as it is immutable (``dataclasses.replace`` would check and copy them all again)."""
        new = copy.copy(self)
        object.__setattr__(new, "vel", _frozen(vel).reshape(self.n, 2))
        return new

    @property
    def speed(self) -> np.ndarray:
        return np.hypot(self.vel[:, 0], self.vel[:, 1])

    @property
    def ego_rows(self) -> np.ndarray:
        return np.flatnonzero(self.is_ego)

    @staticmethod
    def empty(time_s: float = 0.0, signals: Mapping[str, str] | None = None) -> Snapshot:
        z = np.zeros(0)
        return Snapshot(time_s, (), np.zeros((0, 2)), np.zeros((0, 2)), z, z, z, np.zeros(0, bool),
                        signals=signals or {})
