"""The sensors a scenario chooses by name (``ego.sensor``): what the controllers and layers see.
Each is built as ``cls(params, ctx, *, needs_scans, v2v)`` (:class:`sumo_avoid.core.interfaces.Sensor`).

* ``truth``: the controllers read the whole snapshot (``Observation.detections is None``). When a
  layer needs radar scans (the danger-time layer), a front radar with the ``[sensors.radar]``
  parameters scans all the same and its scans go to the layers only (``Observation.scans``).
* ``radar`` (``[sensors.radar]``): each ego's front radar (a rear one with ``rear``, side ones with ``side``);
  controllers get the scans plus the tracker's memory of returns out of view (one fused memory for
  all mounts), and the
  traffic's direction at each ego (its route path's nearest segment), along which returns are
  taken to move unless the map says otherwise (:mod:`.perception`): every return is placed on the map,
  in the normal lane it lies in (``Detections.lane_heading``: ``Road.lane_heading``; none inside a junction),
  and a return labelled a person or cyclist on a sidewalk or walking area, or where people wait at a
  crossing's end (``Detections.walkway``: ``Road.at_kerb``), as an ADAS fuses its radar with its map.

Both hand flock members' V2V messages on (:mod:`.v2v`) when the controller needs them.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from sumo_avoid.road.polyline import route_directions, route_segments
from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import EgoTask, Observation
from sumo_avoid.sensing.log import detections_table
from sumo_avoid.sensing.radar import Radar, RadarParams
from sumo_avoid.sensing.v2v import V2VLink, V2VParams

STREAM = {"front": 4, "rear": 5, "left": 8, "right": 9}  # each mount's noise stream (ctx.rng)


class _Base:
    def __init__(self, ctx=None, v2v: V2VParams | None = None):
        """``ctx`` gives the static obstacles and the random streams; ``v2v`` the controller's V2V
        parameters (a link on the controller's stream ``ctx.rng()``) or None."""
        self.obstacles = tuple(ctx.obstacles) if ctx is not None else ()
        self.v2v = V2VLink(v2v, ctx.rng()) if v2v is not None else None
        self.radars: tuple[Radar, ...] = ()

    def add_ego(self, task: EgoTask) -> None:
        pass

    def remove_ego(self, vid: str) -> None:
        pass

    def stats(self) -> dict:
        return {}

    def tables(self) -> dict:
        log = [d for r in self.radars for d in r.log]
        return {"detections": detections_table(log)} if log else {}

    def _rows(self, snap: Snapshot, ego_ids) -> np.ndarray:
        return np.array([snap.index[v] for v in ego_ids], dtype=int)


class TruthSensor(_Base):
    """Ground truth for the controllers (a front radar for the layers if they need one)."""

    provides_scans = False  # the controllers get no scans

    def __init__(self, params=None, ctx=None, *, needs_scans: bool = False, v2v: V2VParams | None = None):
        """No parameters of its own: the layers' radar has the radar sensor's (``ctx.params["sensors.radar"]``)."""
        super().__init__(ctx, v2v)
        self.radar = Radar(ctx.params["sensors.radar"], ctx.rng(STREAM["front"])) if needs_scans else None
        self.radars = (self.radar,) if self.radar is not None else ()

    def observe(self, snap: Snapshot, ego_ids, ego_speed) -> Observation:
        scans = (self.radar.scan(snap, ego_ids, self.obstacles),) if self.radar is not None else ()
        return Observation(snap, tuple(ego_ids), self._rows(snap, ego_ids), ego_speed, self.obstacles, scans,
                           v2v=self.v2v)


class RadarSensor(_Base):
    """Front radar (+ rear with ``rear``, + left and right with ``side``), one tracker memory, route
    direction per ego."""

    provides_scans = True  # scans for the controllers (so the layers' monitors run)

    def __init__(self, params: RadarParams, ctx, *, needs_scans: bool = True, v2v: V2VParams | None = None):
        super().__init__(ctx, v2v)
        self.radars = tuple(Radar(params, ctx.rng(STREAM[m]), mount=m) for m in params.mounts())
        self.road = getattr(ctx, "road", None)  # the map: where a labelled return stands (sidewalk or road)
        self.front = self.radars[0]  # its tracker is the one memory of all mounts
        self._paths: dict[str, np.ndarray] = {}
        self._seg_key, self._segs = None, None  # route_segments() of the egos in _seg_key

    def add_ego(self, task: EgoTask) -> None:
        self._paths[task.vid] = task.path

    def observe(self, snap: Snapshot, ego_ids, ego_speed) -> Observation:
        ids = tuple(ego_ids)
        rows = self._rows(snap, ids)
        scans = tuple(r.scan(snap, ids, self.obstacles) for r in self.radars)
        if self._seg_key != ids:  # the padded route segments only change with the egos
            self._seg_key, self._segs = ids, route_segments([self._paths.get(v) for v in ids])
        along = route_directions(None, snap.pos[rows], snap.heading[rows], self._segs)
        seen = self.front.objects(scans, along)  # one fused memory over the mounts; a tuple, like scans
        if self.road is not None:  # the returns placed on the map: the lane each lies in, labelled ones at the kerb or not
            seen = tuple(self._placed(d) for d in seen)
        return Observation(snap, ids, rows, ego_speed, self.obstacles, scans, seen, along, self.v2v)

    def _placed(self, det):
        """One scan with its returns placed on the map (their points computed once)."""
        pts = det.points()
        return replace(det, lane_heading=self.road.lane_heading(pts),
                       walkway=None if det.vru is None else self.road.at_kerb(pts))
