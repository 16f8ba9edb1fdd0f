"""The net's elements as immutable records, read once with :mod:`sumolib`: every lane with its
vehicle-class permissions and 3-D shape, the junctions, and the pedestrian crossings and walking
areas (SUMO's internal edges of ``function="crossing"`` / ``"walkingarea"``).

Lanes are keyed by SUMO lane id. ``allow`` is the set of SUMO vehicle classes the lane admits (SUMO's
``allow``/``disallow`` resolved by sumolib against its list of classes); ``function`` is the edge's:
``""`` a normal lane, ``"internal"`` a lane through a junction, ``"crossing"``, ``"walkingarea"``.
A sidewalk is a normal lane that admits only ``pedestrian``; a bike lane one that admits ``bicycle``
and no ``passenger``; a bus lane one that admits ``bus`` and no ``passenger``.

Units: metres, SUMO network coordinates; z is SUMO's elevation (0 on a flat net).
"""
from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

import numpy as np

CROSSING, WALKINGAREA, INTERNAL = "crossing", "walkingarea", "internal"
#: Vulnerable road users in SUMO's classes: the EU ITS Directive 2010/40/EU's "non-motorised road users,
#: such as pedestrians and cyclists, as well as motorcyclists and persons with disabilities or reduced mobility"
VRU_CLASSES = frozenset({"pedestrian", "wheelchair", "bicycle", "scooter", "moped", "motorcycle"})


def _frozen(a) -> np.ndarray:
    arr = np.array(a, dtype=float, copy=True)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True)
class LaneInfo:
    """One SUMO lane."""

    id: str
    edge: str
    index: int  # 0 = rightmost
    function: str  # "" | "internal" | "crossing" | "walkingarea"
    shape: np.ndarray  # (P, 3) centre line x, y, z, m
    width_m: float
    speed_mps: float  # SUMO's speed limit
    allow: frozenset[str]  # SUMO vehicle classes the lane admits

    def allows(self, vclass: str) -> bool:
        return vclass in self.allow


@dataclass(frozen=True)
class JunctionInfo:
    id: str
    type: str  # SUMO's junction type: priority, traffic_light, right_before_left, ...
    shape: np.ndarray  # (K, 2) outline, m (may be empty)


@dataclass(frozen=True)
class CrossingInfo:
    """A pedestrian crossing: where people walk over the carriageway of ``crossed_edges``."""

    id: str  # the crossing's edge id (``:J_c0``)
    junction: str
    lane: str  # its one lane
    shape: np.ndarray  # (P, 2) centre line, m
    width_m: float
    crossed_edges: tuple[str, ...]  # the road edges it crosses


@dataclass(frozen=True)
class RoadElements:
    lanes: Mapping[str, LaneInfo]
    junctions: Mapping[str, JunctionInfo]
    crossings: Mapping[str, CrossingInfo]
    walking_areas: Mapping[str, LaneInfo]  # keyed by lane id
    #: ids of the lanes only people walk on, off the carriageway: sidewalks and walking areas (not crossings)
    walkways: frozenset[str] = frozenset()

    def lanes_allowing(self, vclass: str, functions=("", INTERNAL)) -> tuple[str, ...]:
        """Ids of the lanes (of the given edge functions) that admit ``vclass``, in id order."""
        return tuple(sorted(i for i, ln in self.lanes.items() if ln.function in functions and vclass in ln.allow))


def read_elements(net) -> RoadElements:
    """The records of a :func:`sumolib.net.readNet` network (read with ``withInternal=True``)."""
    lanes, crossings, walking = {}, {}, {}
    for e in net.getEdges(withInternal=True):
        fn = e.getFunction() or ""
        for ln in e.getLanes():
            rec = LaneInfo(ln.getID(), e.getID(), ln.getIndex(), fn, _frozen(ln.getShape3D()), float(ln.getWidth()),
                           float(ln.getSpeed()), frozenset(ln.getPermissions()))
            lanes[rec.id] = rec
            if fn == WALKINGAREA:
                walking[rec.id] = rec
        if fn == CROSSING:
            ln = e.getLanes()[0]
            junction = e.getID()[1:].rsplit("_", 1)[0]
            crossed = tuple(c.getID() for c in e.getCrossingEdges())
            crossings[e.getID()] = CrossingInfo(e.getID(), junction, ln.getID(), _frozen(ln.getShape()),
                                                float(ln.getWidth()), crossed)
    junctions = {}
    for node in net.getNodes():
        shp = node.getShape()
        junctions[node.getID()] = JunctionInfo(node.getID(), node.getType(),
                                               _frozen(shp if shp else np.zeros((0, 2))).reshape(-1, 2))
    walkways = frozenset(i for i, ln in lanes.items()
                         if ln.function == WALKINGAREA or (ln.function != CROSSING and ln.allow == {"pedestrian"}))
    return RoadElements(MappingProxyType(lanes), MappingProxyType(junctions), MappingProxyType(crossings),
                        MappingProxyType(walking), walkways)
