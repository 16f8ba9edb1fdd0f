"""A forward radar emulator (SPEC §4, seed 004 §1.1) for all egos at once.

Each ego carries one radar at the centre of its front bumper, boresight along the ego's heading,
and optionally (``rear = true``) a second one at the rear bumper looking back, and (``side =
true``) one on each flank, mid-side, looking left / right with their own field of view and range
(``side_fov_deg``, ``side_range_m``: blind-spot radars, the only ones that see a car alongside).
Each mount is a :class:`Radar` with its own scan; one tracker memory serves them all; the
danger-time layer reads only the front one.
Per scan it reports, for every target it can see, one return at the target's nearest visible
point: its **range**, its **azimuth** (rad, CCW from the boresight) and the **radial speed** (the
target's velocity relative to the ego projected on the line of sight, m/s; negative = closing).
Targets are footprints (other vehicles' oriented rectangles and static obstacle polygons), not
centres.

Model, per ego and scan:

1. *Candidates*: targets whose centre lies within ``max_range_m`` plus their half-diagonal, on the
   ego's level (:mod:`sumo_avoid.core.levels`: a car on a bridge over the ego neither returns nor
   hides anything, the deck is in the way; static obstacles are on every level).
2. *Angular intervals*: every candidate's vertices are converted to azimuths; the candidate covers
   [min, max] (clipped to the field of view). Targets straddling the rear (span > 180 degrees) or
   containing the sensor are dropped (the field of view is forward, < 180 degrees).
3. *Occlusion*: all vertex azimuths of all candidates (and the feet of the perpendiculars from
   the sensor on their edges) cut the field of view into elementary sectors; within one sector the set of covering targets is fixed and, footprints being disjoint
   and convex, so is their depth order. The target hit first by the sector's middle ray owns the
   sector. A target is seen iff it owns a sector: fully hidden targets vanish, partly hidden ones
   are measured on their visible part (its nearest point: exact, since within a sector the
   owner's boundary is one straight piece whose distance is monotone in the azimuth).
4. *Limits*: reported only if the true range <= ``max_range_m``.
5. *Imperfections* (numpy Generator, seeded from the scenario seed): each seen target is detected
   with probability ``detection_prob``; Gaussian noise on range, radial speed and azimuth; the
   azimuth is quantised to ``angular_resolution_deg``; false alarms (Poisson, mean
   ``false_alarm_rate`` per scan and ego) are stationary clutter uniform in range and azimuth.
6. *Update period*: a new scan every ``update_period_s``; in between the last scan is held.
7. *Memory* (controllers only, :mod:`.tracker`): returns that left the field of view are coasted
   for ``memory_s`` so a car beside the ego is not forgotten the moment it leaves the beam.

Not modelled: merging of targets closer than the angular resolution, multipath, multiple
reflections per target, elevation. ``Detections.target`` (the true id) is for evaluation only.

Steps 5-7 are numpy here; the footprints, step 1 (a sweep along one axis instead of a k-d tree) and
steps 2-4 run in compiled loops over egos, :mod:`.occlusion` (numba), with the detections of the
numpy / k-d tree formulation they replaced and its values within 1e-12 relative (kept as the
reference in tests/sensing/radar_reference.py; numpy's SIMD kernels round differently by CPU).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from sumo_avoid.core.config import FieldError, field_doc
from sumo_avoid.core.geometry import wrap_angle
from sumo_avoid.core.levels import apart_pairs, same_level
from sumo_avoid.core.types import Detections
from sumo_avoid.sensing import occlusion
from sumo_avoid.sensing.tracker import Tracker

_BIG = 1e18


@dataclass(frozen=True)
class RadarParams:
    max_range_m: float = field_doc(100.0, doc="maximum range, m (seed 004: 100 m)")
    fov_deg: float = field_doc(90.0, doc="full horizontal field of view, degrees (< 180)")
    angular_resolution_deg: float = field_doc(1.0, doc="azimuth quantisation step, degrees (0 = none)")
    update_period_s: float = field_doc(0.1, doc="time between scans, s (held in between)")
    range_sigma_m: float = field_doc(0.1, doc="range noise standard deviation, m")
    speed_sigma_mps: float = field_doc(0.1, doc="radial-speed noise standard deviation, m/s")
    azimuth_sigma_deg: float = field_doc(0.0, doc="azimuth noise standard deviation, degrees")
    detection_prob: float = field_doc(1.0, doc="probability that a visible target is reported in a scan")
    false_alarm_rate: float = field_doc(0.0, doc="mean false alarms per scan and ego (Poisson)")
    memory_s: float = field_doc(8.0, doc="controllers also get returns lost from view for this long, coasted (0 = off), s")
    log_detections: bool = field_doc(False, doc="keep every scan's detections (detections.csv)")
    rear: bool = field_doc(False, doc="also a rear-facing radar at the rear bumper centre, same parameters "
                                      "(lane-change / blind-spot assist: sees traffic closing from behind)")
    side: bool = field_doc(False, doc="also a side radar on each flank (mid-side, boresight 90 degrees left / "
                                      "right; blind-spot monitoring: sees a car alongside, which front and rear "
                                      "radars cannot), with side_fov_deg and side_range_m")
    side_fov_deg: float = field_doc(150.0, doc="full horizontal field of view of each side radar, degrees (< 180)")
    side_range_m: float = field_doc(40.0, doc="maximum range of each side radar, m")
    person_range_factor: float = field_doc(0.42, positive=True, doc="a person is seen only within this fraction "
                                           "of the range (radar equation, range ~ RCS^(1/4): -5 dBsm against a "
                                           "car's +10 dBsm; docs/radar.md)")
    person_detection_prob: float = field_doc(0.9, doc="probability that a visible person is reported in a scan "
                                                      "(on top of detection_prob)")
    cyclist_range_factor: float = field_doc(0.56, positive=True, doc="... a cyclist (vehicle class bicycle): "
                                            "0 dBsm against +10 dBsm")
    vru_label_prob: float = field_doc(1.0, doc="probability that a reported person's or cyclist's return is "
                                               "labelled a VRU (small cross-section); unlabelled, the controllers "
                                               "keep a car's margin to it (docs/radar.md)")

    def __post_init__(self):
        if self.max_range_m <= 0:
            raise ValueError("radar.max_range_m > 0")
        if not 0 < self.fov_deg < 180:
            raise ValueError("0 < radar.fov_deg < 180")
        if self.angular_resolution_deg < 0 or self.update_period_s < 0:
            raise ValueError("radar.angular_resolution_deg and radar.update_period_s >= 0")
        if min(self.range_sigma_m, self.speed_sigma_mps, self.azimuth_sigma_deg, self.false_alarm_rate,
               self.memory_s) < 0:
            raise ValueError("radar noise sigmas and false_alarm_rate >= 0")
        if not 0 <= self.detection_prob <= 1:
            raise ValueError("0 <= radar.detection_prob <= 1")
        if not 0 < self.side_fov_deg < 180:
            raise ValueError("0 < radar.side_fov_deg < 180")
        if self.side_range_m <= 0:
            raise ValueError("radar.side_range_m > 0")
        for key in ("person_detection_prob", "vru_label_prob"):
            if not 0 <= getattr(self, key) <= 1:
                raise FieldError(key, "a probability in [0, 1]", getattr(self, key))
        for key in ("person_range_factor", "cyclist_range_factor"):
            if getattr(self, key) > 1:
                raise FieldError(key, "a fraction of the range in (0, 1] (a person reflects less than a car)",
                                 getattr(self, key))

    def mounts(self) -> tuple[str, ...]:
        """The radars these parameters fit on each ego, front first."""
        return ("front",) + (("rear",) if self.rear else ()) + (("left", "right") if self.side else ())

    def view(self, mount: str) -> tuple[float, float]:
        """(full field of view, degrees; range, m) of the radar at ``mount``."""
        return (self.side_fov_deg, self.side_range_m) if mount in SIDES else (self.fov_deg, self.max_range_m)


def targets(snap, obstacles=()):
    """Everything a radar can see: vehicles' footprints (4 corners) and static polygons, padded to
    K vertices by repeating the last one. Returns polys (N, K, 2), velocities (N, 2), ids (N,),
    centres (N, 2) (vertex means) and circumscribed radii (N,)."""
    corners, centre, radius = occlusion.boxes(snap.pos, np.cos(snap.heading), np.sin(snap.heading), snap.length, snap.width)
    ids = tuple(snap.ids)
    if not len(obstacles):
        return corners, snap.vel, ids, centre, radius
    polys = [np.asarray(o, float).reshape(-1, 2) for o in obstacles]
    K = max([4] + [len(o) for o in polys])
    pad = [np.concatenate([o, np.repeat(o[-1:], K - len(o), axis=0)])[None] for o in polys]
    allo = np.concatenate(pad)
    oc = allo.mean(axis=1)
    orad = np.sqrt(((allo - oc[:, None]) ** 2).sum(-1)).max(axis=1)
    allc = np.concatenate([np.concatenate([corners, np.repeat(corners[:, -1:], K - 4, axis=1)], axis=1), allo])
    vel = np.concatenate([snap.vel, np.zeros((len(polys), 2))])
    vel.flags.writeable = False  # read-only like a Snapshot's: the kernel is compiled for one kind of array
    return (allc, vel, ids + tuple(f"obstacle{i}" for i in range(len(polys))),
            np.concatenate([centre, oc]), np.concatenate([radius, orad]))


MOUNTS = ("front", "rear", "left", "right")
SIDES = ("left", "right")
# boresight relative to the heading, rad; the front and rear radars sit at the bumper's centre, the
# side radars at the middle of the flank (+1 left, -1 right)
_TURN = {"front": 0.0, "rear": math.pi, "left": 0.5 * math.pi, "right": -0.5 * math.pi}
_FLANK = {"left": 1.0, "right": -1.0}


class Radar:
    """Scans every ego's surroundings from one mount; stateful only for the update period and the log."""

    def __init__(self, params: RadarParams, rng: np.random.Generator, mount: str = "front"):
        if mount not in MOUNTS:
            raise ValueError(f"radar mount must be one of {MOUNTS}")
        fov, rng_m = params.view(mount)
        # this mount's own field of view and range (a side radar's differ from the front's)
        self.p = params if mount not in SIDES else replace(params, fov_deg=fov, max_range_m=rng_m)
        self.mount = mount
        self.rng = rng
        self._last: Detections | None = None
        self.log: list[Detections] = []
        occlusion.warm()  # load the compiled kernel now, with the set-up, not inside the first step
        self._scan, self._candidates = occlusion.scan, occlusion.candidates
        # the front radar keeps the one memory of every mount (each judged by its own view)
        views = {m: params.view(m) for m in params.mounts()}
        self.tracker = (Tracker(params.memory_s, params.fov_deg, params.max_range_m, views=views)
                        if params.memory_s > 0 and mount == "front" else None)

    def objects(self, det, along=None):
        """What controllers get: the scan plus remembered returns now out of view (sensors.tracker).
        ``det`` may be a tuple (this radar's scan, then other mounts' scans): one fused memory.
        ``along`` (E,) rad: the traffic's direction at each ego (its route), for coasting."""
        return self.tracker.update(det, along) if self.tracker is not None else det

    def scan(self, snap, ego_ids, obstacles=(), *, force: bool = False) -> Detections:
        """Detections of the egos ``ego_ids`` in ``snap``; static ``obstacles`` are (k,2) polygons."""
        ego_ids = tuple(ego_ids)
        last = self._last
        if (not force and last is not None and last.ego_ids == ego_ids
                and snap.time_s - last.time_s < self.p.update_period_s - 1e-9):
            return last
        det = self.measure(snap, ego_ids, obstacles)
        self._last = det
        if self.p.log_detections:
            self.log.append(det)
        return det

    # --- the physics -----------------------------------------------------------------------
    def pose(self, snap, rows):
        """Sensor positions (E, 2) (bumper or flank centres), boresights (E,) rad and their unit vectors (E, 2)."""
        h = snap.heading[rows]
        hd = h if self.mount == "front" else wrap_angle(h + _TURN[self.mount])  # rear looks back, sides sideways
        fwd = np.column_stack([np.cos(hd), np.sin(hd)])
        if self.mount in SIDES:
            left = np.column_stack([-np.sin(h), np.cos(h)])
            return snap.pos[rows] + (_FLANK[self.mount] * 0.5 * snap.width[rows])[:, None] * left, hd, fwd
        return snap.pos[rows] + 0.5 * snap.length[rows][:, None] * fwd, hd, fwd

    def measure(self, snap, ego_ids, obstacles=()) -> Detections:
        p = self.p
        rows = np.array([snap.index[v] for v in ego_ids], dtype=int)
        spos, hd, fwd = self.pose(snap, rows)
        svel = snap.vel[rows]
        polys, vel, ids, centre, radius = targets(snap, obstacles)
        half = math.radians(p.fov_deg) / 2
        e, n = self._candidates(spos, fwd, centre, radius, rows, p.max_range_m, math.cos(half), math.sin(half))
        if snap.levels:  # no return from, and no shadow of, a road user on another level (core.levels)
            vehicle = n < snap.n
            m = np.where(vehicle, n, 0)
            keep = ~vehicle | (same_level(snap.z[rows[e]], snap.z[m]) &
                               ~apart_pairs(snap.apart, [snap.lane[r] for r in rows[e]], [snap.lane[r] for r in m]))
            e, n = e[keep], n[keep]
        ptr = np.concatenate([[0], np.cumsum(np.bincount(e, minlength=len(rows)))]).astype(np.int64)
        ego, tgt, rng, az, vr = self._scan(spos, hd, svel, polys, vel, ptr, n, half, p.max_range_m)
        small = None
        if snap.is_person.any() or "bicycle" in snap.vclass:  # small targets: shorter range, missed more often
            ego, tgt, rng, az, vr, small = self._small_targets(snap, ego, tgt, rng, az, vr)
        det = Detections(snap.time_s, tuple(ego_ids), spos, hd, svel, ego, rng, az, vr,
                         tuple([ids[i] for i in tgt.tolist()]), mount=self.mount, vru=small)
        return self._imperfect(det)

    def _small_targets(self, snap, ego, tgt, range_m, az, vr):
        """Drop returns of persons beyond ``person_range_factor`` x the range (cyclists: their factor)
        and, of the persons left, each with probability 1 - ``person_detection_prob``; label the
        returns kept: a person's or cyclist's is labelled a VRU with probability ``vru_label_prob``
        (its small cross-section, as an object-level radar's classifier reports it)."""
        p = self.p
        vehicle = tgt < snap.n
        row = np.where(vehicle, tgt, 0)
        person = vehicle & snap.is_person[row]
        cyclist = vehicle & (np.asarray(snap.vclass, dtype=object)[row] == "bicycle") if snap.n else person
        reach = np.where(person, p.person_range_factor, np.where(cyclist, p.cyclist_range_factor, 1.0)) * p.max_range_m
        keep = range_m <= reach
        if p.person_detection_prob < 1 and (person & keep).any():
            k = np.flatnonzero(person & keep)
            keep[k] = self.rng.random(len(k)) < p.person_detection_prob
        small = (person | cyclist)[keep]
        if p.vru_label_prob < 1 and small.any():
            k = np.flatnonzero(small)
            small[k] = self.rng.random(len(k)) < p.vru_label_prob
        return ego[keep], tgt[keep], range_m[keep], az[keep], vr[keep], small

    def _imperfect(self, det: Detections) -> Detections:
        p, g = self.p, self.rng
        D = det.n
        small = det.vru
        if p.detection_prob < 1:
            keep = g.random(D) < p.detection_prob
            e, r, a, v = det.ego[keep], det.range_m[keep], det.azimuth_rad[keep], det.radial_speed_mps[keep]
            tgt = tuple([t for t, k in zip(det.target, keep.tolist()) if k])
            small = None if small is None else small[keep]
        else:
            e, r, a, v, tgt = det.ego, det.range_m, det.azimuth_rad, det.radial_speed_mps, det.target
        r = r + g.normal(0.0, p.range_sigma_m, len(r)) if p.range_sigma_m else r
        v = v + g.normal(0.0, p.speed_sigma_mps, len(v)) if p.speed_sigma_mps else v
        a = a + g.normal(0.0, math.radians(p.azimuth_sigma_deg), len(a)) if p.azimuth_sigma_deg else a
        if p.false_alarm_rate > 0:
            E = len(det.ego_ids)
            nfa = g.poisson(p.false_alarm_rate, E)
            fe = np.repeat(np.arange(E), nfa)
            half = math.radians(p.fov_deg) / 2
            fr = g.uniform(0.0, p.max_range_m, len(fe))
            fa = g.uniform(-half, half, len(fe))
            # stationary clutter: seen closing at the ego's speed along the line of sight
            sv = det.sensor_vel[fe]
            fv = -(sv[:, 0] * np.cos(det.sensor_heading[fe] + fa) + sv[:, 1] * np.sin(det.sensor_heading[fe] + fa))
            e, r, a, v = (np.concatenate(x) for x in ((e, fe), (r, fr), (a, fa), (v, fv)))
            tgt = tgt + ("",) * len(fe)
            small = None if small is None else np.concatenate([small, np.zeros(len(fe), bool)])  # clutter: unlabelled
        if p.angular_resolution_deg > 0:
            step = math.radians(p.angular_resolution_deg)
            a = np.round(a / step) * step
        r = np.clip(r, 0.0, None)
        return Detections(det.time_s, det.ego_ids, det.sensor_pos, det.sensor_heading, det.sensor_vel,
                          e.astype(int), r, a, v, tgt, det.mount, small)
