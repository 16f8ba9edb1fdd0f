"""Per-step recording of the world into arrays; becomes pandas tables after the run: the vehicles
(:meth:`Recorder.table`, ``trajectories.csv``), the persons outside vehicles (:meth:`Recorder.persons`,
``persons.csv``, the same columns), and each road user's SUMO class (:meth:`Recorder.classes`).

Columns: :data:`COLUMNS` (``lane``, ``lane_pos``: where SUMO has the vehicle, its lane id and
the front bumper's position along it; "" / empty where SUMO has it on no lane), and ``z`` (m, the
height SUMO gives the road user's position, :mod:`sumo_avoid.core.levels`) after them, only when some
z is not 0 (a flat net's recording is as before). Egos are always recorded; other vehicles only within ``record_radius_m`` of an ego (0 = all), to
keep big-traffic runs small. Headings are written wrapped to (-pi, pi]. SUMO's own collision reports are kept beside, one event per pair and
contact episode (consecutive steps), the same rule as the plug-in's own events.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from sumo_avoid.core.geometry import near_any
from sumo_avoid.core.snapshot import Snapshot

COLUMNS = ["step", "time_s", "id", "is_ego", "x", "y", "vx", "vy", "speed", "heading", "length", "width", "lane",
           "lane_pos"]


def wrap_angle(a) -> np.ndarray:
    """Angles (rad) wrapped to (-pi, pi]: SUMO's compass angle turned into a math heading spans
    (-3 pi/2, pi/2], and an actuator's integrated heading any multiple of 2 pi."""
    w = np.pi - np.mod(np.pi - np.asarray(a, float), 2.0 * np.pi)
    return np.where(w <= -np.pi, w + 2.0 * np.pi, w)


class Recorder:
    def __init__(self, record_radius_m: float = 0.0):
        self.radius = record_radius_m
        self._chunks: list[tuple] = []
        self._person_chunks: list[tuple] = []
        self._classes: dict[str, str] = {}  # id -> SUMO vehicle class of every recorded road user
        self._sumo_events: list[dict] = []
        self._sumo_last: dict[tuple[str, str], int] = {}
        self._signals: list[tuple[float, str, str]] = []
        self._signal_now: dict[str, str] = {}
        self._strings: dict[str, str] = {}  # one str object per id and lane id, however many steps record it

    def _canonical(self, values, idx: np.ndarray) -> np.ndarray:
        """values[idx] as an object array of one str object per distinct value: SUMO hands out new str objects
        every step, and holding those made a city hour's recording (100 egos, ~2,500 road users within reach)
        several GB larger than its numbers."""
        keep = self._strings.setdefault
        out = np.empty(len(idx), dtype=object)
        out[:] = [keep(v, v) for v in (str(values[i]) for i in idx.tolist())]  # str() of a str is itself
        return out

    def record(self, step: int, snap: Snapshot) -> None:
        for tls, state in snap.signals.items():
            if self._signal_now.get(tls) != state:
                self._signal_now[tls] = state
                self._signals.append((snap.time_s, tls, state))
        if snap.n == 0:
            return
        keep = snap.is_ego.copy()
        if self.radius > 0 and keep.any():
            keep |= near_any(snap.pos, snap.pos[snap.is_ego], self.radius)
        elif self.radius <= 0:
            keep[:] = True
        for chunks, rows in ((self._chunks, keep & ~snap.is_person), (self._person_chunks, keep & snap.is_person)):
            idx = np.flatnonzero(rows)
            if len(idx) == 0:
                continue
            ids = self._canonical(snap.ids, idx)
            self._classes.update(zip(ids.tolist(), np.array(snap.vclass, dtype=object)[idx].tolist()))
            chunks.append((step, snap.time_s, ids, snap.is_ego[idx], snap.pos[idx], snap.vel[idx],
                           snap.heading[idx], snap.length[idx], snap.width[idx],
                           self._canonical(snap.lane, idx), snap.lane_pos[idx], snap.z[idx]))

    def record_sumo_collisions(self, step: int, collisions) -> None:
        for c in collisions:
            pair = tuple(sorted((c.collider, c.victim)))
            if self._sumo_last.get(pair) != step - 1 and self._sumo_last.get(pair) != step:
                self._sumo_events.append({"step": step, "time_s": c.time_s, "a": pair[0], "b": pair[1],
                                          "collider": c.collider, "victim": c.victim, "type": c.kind,
                                          "lane": c.lane})
            self._sumo_last[pair] = step

    def table(self) -> pd.DataFrame:
        """The vehicles: one row per recorded vehicle per step (:data:`COLUMNS`)."""
        return _frame(self._chunks)

    def persons(self) -> pd.DataFrame:
        """The persons outside vehicles, as :meth:`table` (``is_ego`` always false)."""
        return _frame(self._person_chunks)

    def classes(self) -> dict[str, str]:
        """id -> SUMO vehicle class ("pedestrian" for a person) of every road user recorded."""
        return dict(self._classes)

    def signals(self) -> pd.DataFrame:
        """Traffic light states, one row per change (and the first state of each light)."""
        return pd.DataFrame(self._signals, columns=["time_s", "tls", "state"])

    def sumo_events(self) -> pd.DataFrame:
        return pd.DataFrame(self._sumo_events, columns=["step", "time_s", "a", "b", "collider", "victim", "type", "lane"])


def _frame(chunks: list[tuple]) -> pd.DataFrame:
    if not chunks:
        return pd.DataFrame({c: pd.Series(dtype=float) for c in COLUMNS})
    sizes = [len(c[2]) for c in chunks]
    pos = np.concatenate([c[4] for c in chunks])
    vel = np.concatenate([c[5] for c in chunks])
    z = np.concatenate([c[11] for c in chunks])
    table = pd.DataFrame({
        "step": np.repeat([c[0] for c in chunks], sizes).astype(np.int64),
        "time_s": np.repeat([c[1] for c in chunks], sizes),
        "id": np.concatenate([c[2] for c in chunks]),  # str objects (an .astype(str) made a fixed-width copy of
        # the longest id per row: GBs for a city hour)
        "is_ego": np.concatenate([c[3] for c in chunks]),
        "x": pos[:, 0], "y": pos[:, 1], "vx": vel[:, 0], "vy": vel[:, 1],
        "speed": np.hypot(vel[:, 0], vel[:, 1]),
        "heading": wrap_angle(np.concatenate([c[6] for c in chunks])),
        "length": np.concatenate([c[7] for c in chunks]),
        "width": np.concatenate([c[8] for c in chunks]),
        "lane": np.concatenate([c[9] for c in chunks]),
        "lane_pos": np.concatenate([c[10] for c in chunks]),
    })
    if np.any(z != 0.0):  # a net with heights (bridges, tunnels: core.levels); a flat one's table stays as it was
        table["z"] = z
    return table
