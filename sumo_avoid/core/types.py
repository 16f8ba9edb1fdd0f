"""The data that flows through one step of the rollout, as immutable, fully typed records.

snapshot (:class:`~sumo_avoid.core.snapshot.Snapshot`) -> sensor -> :class:`Observation` ->
controller -> command ((E, 2) desired velocity, m/s) -> layers -> actuator -> :class:`Motion`.
A plug-in is told about each ego once, when the plug-in takes it over (:class:`EgoTask`).
Nothing here talks to SUMO.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from sumo_avoid.core.snapshot import Snapshot

if TYPE_CHECKING:  # type-only: the road's route records (sumo_avoid.road.route), no runtime import
    from sumo_avoid.road.route import LanePiece, RouteLink


@dataclass(frozen=True)
class EgoTask:
    vid: str
    goal: np.ndarray  # (2,) m
    path: np.ndarray  # (P, 2) reference polyline along the ego's route, m
    cruise_speed_mps: float
    links: tuple[RouteLink, ...] = ()  # junction links along the path, in route order
    speed_limits: np.ndarray | None = None  # (K, 2 or 3) [s where a lane piece starts, its speed limit, 1: internal lane], m, m/s
    lanes: tuple[LanePiece, ...] = ()  # the path's lane pieces, in route order
    width_m: float = 1.8  # the ego's width (SUMO's vehicle type), m
    length_m: float = 5.0  # ... and length, m
    vclass: str = "passenger"  # its SUMO vehicle class: which lanes it may use (LanePiece.allowed)
    walkways: frozenset[str] = frozenset()  # the net's sidewalks and walking areas (lane ids): people there are off the carriageway


@dataclass(frozen=True)
class Detections:
    """One scan of all egos' radars: D detections, each row belongs to ego ``ego[i]``."""

    time_s: float
    ego_ids: tuple[str, ...]  # the egos scanned (index space of ``ego``)
    sensor_pos: np.ndarray  # (E, 2) radar positions (bumper centres), m
    sensor_heading: np.ndarray  # (E,) boresight, rad CCW from +x
    sensor_vel: np.ndarray  # (E, 2) ego velocities, m/s
    ego: np.ndarray  # (D,) int index into ego_ids
    range_m: np.ndarray  # (D,)
    azimuth_rad: np.ndarray  # (D,) CCW from the boresight
    radial_speed_mps: np.ndarray  # (D,) relative speed along the line of sight (< 0 closing)
    target: tuple[str, ...] = field(default=())  # (D,) true target id, "" = false alarm. EVALUATION ONLY
    mount: str = "front"  # which radar: "front" (boresight = heading), "rear" (heading + pi), "left" / "right" (heading + / - pi/2)
    vru: np.ndarray | None = None  # (D,) bool: the return is labelled a person or cyclist (small cross-section); None = none are
    walkway: np.ndarray | None = None  # (D,) bool: the return lies on a sidewalk or walking area of the map; None = none does
    lane_heading: np.ndarray | None = None  # (D,) rad: direction of the map's lane the return lies in, NaN none; None = not placed

    @property
    def n(self) -> int:
        return len(self.range_m)

    def vru_mask(self) -> np.ndarray:
        """(D,) bool: returns labelled as a person or cyclist (all False when the scan has no labels)."""
        return np.zeros(self.n, bool) if self.vru is None else self.vru

    def walkway_mask(self) -> np.ndarray:
        """(D,) bool: returns on a sidewalk or walking area (all False when not known)."""
        return np.zeros(self.n, bool) if self.walkway is None else self.walkway

    def points(self) -> np.ndarray:
        """(D, 2) world positions of the detections, m."""
        a = self.sensor_heading[self.ego] + self.azimuth_rad
        return self.sensor_pos[self.ego] + self.range_m[:, None] * np.column_stack([np.cos(a), np.sin(a)])

    def of(self, vid: str) -> np.ndarray:
        """Indices of the detections of ego ``vid``."""
        return np.flatnonzero(self.ego == self.ego_ids.index(vid)) if vid in self.ego_ids else np.zeros(0, int)


class NeighbourLink(Protocol):
    """V2V: what each controlled vehicle knows of itself and receives from the others (flocking).

    ``states(snapshot, rows)`` -> (own_pos, own_vel, nb_pos, nb_vel), each (E, 2), rows aligned with
    ``rows``: own state as sensed now, the state the others receive (delayed, noisy). A controller
    calls it when it updates (the link keeps the message history and the noise state)."""

    def states(self, snap: Snapshot, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class Observation:
    """What the sensor hands the controller (and the layers) at one step.

    With ground truth (``detections is None``) a controller reads other vehicles from the snapshot;
    with radar it takes them from ``detections`` (sensing.perception), never from the snapshot's
    other rows (``Detections.target`` is for evaluation only)."""

    snapshot: Snapshot
    ego_ids: tuple[str, ...]  # egos to control, in the order of the returned velocities
    ego_rows: np.ndarray  # (E,) int, their rows in the snapshot
    ego_speed: np.ndarray  # (E,) signed speed the actuator holds (negative = reversing), m/s
    obstacles: tuple[np.ndarray, ...] = ()  # static obstacle polygons, each (k, 2) m
    scans: tuple[Detections, ...] = ()  # this step's raw radar scans, one per mount (front first)
    detections: tuple[Detections, ...] | None = None  # radar: scans + tracker memory, per mount; truth: None
    route_heading: np.ndarray | None = None  # radar: (E,) rad, the traffic's direction at each ego
    v2v: NeighbourLink | None = None  # controllers that declare Needs(v2v=True)

    def index(self, vid: str) -> int:
        """Position of ego ``vid`` in ``ego_ids`` (and in the command)."""
        return self.ego_ids.index(vid)


@dataclass(frozen=True)
class Motion:
    pos: np.ndarray  # (E, 2) new centre, m
    heading: np.ndarray  # (E,) new heading, rad
    speed: np.ndarray  # (E,) new signed speed along the heading, m/s (negative = reversing)


@dataclass(frozen=True)
class Needs:
    """What a controller declares it needs (data, read by the assembly; the loop never probes)."""

    goals: bool = True  # egos are retired at their goal (a flock has none)
    v2v: bool = False  # flock members' states over V2V (Observation.v2v)
    # the plug-in drives the egos (SUMO's safety checks off, the actuator's motion applied each step);
    # False: SUMO's own driver models drive them and the plug-in only records them (controller "sumo")
    drives: bool = True


@dataclass(frozen=True)
class Keys:
    """Top-level ``metrics.json`` keys a plug-in writes, declared as data (a metric's ``keys``, a
    controller's or layer's ``stats_keys``), so that names a user gives (suite criteria) are checked
    before anything runs. ``numeric``: a number, true/false or null per run; ``text``: a string per
    run (both ledger columns); ``nested``: lists and objects, kept only in ``metrics.json``.
    tests/metrics/test_metric_keys.py compares the declarations with what real runs write."""

    numeric: tuple[str, ...] = ()
    nested: tuple[str, ...] = ()
    text: tuple[str, ...] = ()

    def __or__(self, other: Keys) -> Keys:
        """Both sets; a key both declare takes ``other``'s kind (a later metric wins a shared key)."""
        kind = {k: i for keys in (self, other) for i, group in enumerate((keys.numeric, keys.nested, keys.text))
                for k in group}
        return Keys(*(tuple(k for k, i in kind.items() if i == n) for n in range(3)))

    @property
    def names(self) -> frozenset[str]:
        return frozenset(self.numeric + self.nested + self.text)
