"""Danger-time safety layer (SPEC §4, seed 004 §1.2): wraps any controller's desired velocity.

The seed: the host computer feeds the radar's range and relative speed into a danger-time model;
as the danger reaches different levels it issues a warning, or limits speed, or brakes; with
nothing ahead within 100 m the car accelerates back to its cruise speed. The seed gives no numbers,
so the levels below are ours (scenario ``[layers.danger_time]`` table), with these defaults and sources:

    t_d = range / closing speed        (targets in the ego's path, closing speed > 0 only)

* ``warning``  t_d <= ``warning_s`` = 3.0 s. NHTSA's NCAP forward-collision-warning test
  (Federal Register 73 FR 40016, 2008) requires the alert by TTC 2.1 s (stopped lead), 2.0 s
  (slower lead) and 2.4 s (braking lead); 3.0 s clears all three with margin. No action, counted.
* ``reduce``   t_d <= ``reduce_s`` = 2.0 s: comfortable braking at ``reduce_decel_mps2`` = 3 m/s^2
  (about 0.3 g, the usual upper bound of comfortable deceleration).
* ``brake``    t_d <= max(``brake_s`` = 1.0 s, v_c / (2 a) + ``reaction_s``): full braking (desired
  velocity 0; the actuator brakes at its ``max_decel_mps2``). 1.0 s is in the range of AEB full-
  braking triggers; the kinematic term ``v_c / (2 a)`` is exactly the danger time at which the
  stopping distance v_c^2 / (2 a) equals the range (``a`` = ``brake_plan_decel_mps2`` = 6 m/s^2,
  below the 8 m/s^2 actuator limit to leave margin for noise and the scan period), so a stopped
  obstacle revealed late is still braked for in time when that is physically possible.

"In the path": the detection point lies ahead of the sensor and within half the ego's width plus
``path_margin_m`` of its heading line. When nothing is in range (or nothing closing in the path)
the layer passes the controller's velocity through unchanged, so the ego accelerates back to the
controller's cruise speed at the actuator's acceleration limit. Counters (``metrics.json``):
``radar_warnings`` and ``radar_brakes`` count episodes (entries into warning-or-worse and into
full braking, per ego), ``radar_reductions`` entries into speed reduction, ``min_danger_time_s``
the smallest danger time seen (None if no closing target was ever in the path). While anything
in the path is within ``standstill_gap_m`` the brake is held (no creeping up to a stopped car).
Full braking, once triggered, is held until t_d > ``warning_s`` and the in-path gap exceeds twice
``standstill_gap_m`` (hysteresis).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.config import field_doc
from sumo_avoid.core.types import Keys

NONE, WARNING, REDUCE, BRAKE = 0, 1, 2, 3


@dataclass(frozen=True)
class DangerTimeParams:
    warning_s: float = field_doc(3.0, doc="warn at danger time <= this, s (NHTSA NCAP FCW: 2.0-2.4 s)")
    reduce_s: float = field_doc(2.0, doc="reduce speed at danger time <= this, s")
    brake_s: float = field_doc(1.0, doc="full braking at danger time <= this (at least), s")
    brake_plan_decel_mps2: float = field_doc(6.0, doc="full braking also when range <= v_c^2/(2 a): a, m/s^2")
    reaction_s: float = field_doc(0.3, doc="latency added to the kinematic braking threshold, s")
    reduce_decel_mps2: float = field_doc(3.0, doc="deceleration of the speed-reduction level, m/s^2")
    path_margin_m: float = field_doc(0.5, doc="lateral margin beyond half the ego width for 'in the path', m")
    standstill_gap_m: float = field_doc(2.0, doc="hold the brake while anything in the path is this close, m")

    def __post_init__(self):
        if not self.warning_s >= self.reduce_s >= self.brake_s >= 0:
            raise ValueError("warning_s >= reduce_s >= brake_s >= 0")
        if self.brake_plan_decel_mps2 <= 0 or self.reduce_decel_mps2 <= 0 or self.reaction_s < 0:
            raise ValueError("decelerations > 0, reaction_s >= 0")


def danger_time(det, ego_width: np.ndarray, margin_m: float):
    """Per ego (E,): the smallest danger time over closing in-path detections (inf if none), s,
    the closing speed of that detection (0 if none), m/s, and the smallest in-path range (any
    relative speed; inf if none), m."""
    E = len(det.ego_ids)
    td, vc, gap = np.full(E, np.inf), np.zeros(E), np.full(E, np.inf)
    if det.n == 0:
        return td, vc, gap
    x = det.range_m * np.cos(det.azimuth_rad)
    y = det.range_m * np.sin(det.azimuth_rad)
    closing = -det.radial_speed_mps
    ahead = (x > 0) & (np.abs(y) <= 0.5 * ego_width[det.ego] + margin_m)
    np.minimum.at(gap, det.ego, np.where(ahead, det.range_m, np.inf))
    in_path = ahead & (closing > 1e-6)
    t = np.where(in_path, det.range_m / np.where(in_path, closing, 1.0), np.inf)
    np.minimum.at(td, det.ego, t)
    mine = in_path & (t == td[det.ego])
    np.maximum.at(vc, det.ego[mine], closing[mine])
    return td, vc, gap


def levels(td: np.ndarray, v_close: np.ndarray, p: DangerTimeParams, gap=None) -> np.ndarray:
    """(E,) level per ego from danger times td (s), closing speeds v_close (m/s) and in-path gaps (m)."""
    t_brake = np.maximum(p.brake_s, v_close / (2.0 * p.brake_plan_decel_mps2) + p.reaction_s)
    hold = np.zeros(len(td), bool) if gap is None else gap <= p.standstill_gap_m
    return np.select([(td <= t_brake) | hold, td <= p.reduce_s, td <= p.warning_s], [BRAKE, REDUCE, WARNING], NONE)


class DangerTimeLayer:
    """Limits the desired velocities of the egos by their radar danger time; counts interventions.

    As a :class:`~sumo_avoid.core.interfaces.Layer` it reads the front radar scan of the step
    (``Observation.scans[0]``); with ``enforce=False`` it only counts (a monitor: the command passes
    unchanged)."""

    needs_scans = True
    monitor_when_scans = True  # not chosen, it counts all the same when the sensor provides scans
    stats_keys = Keys(("radar_warnings", "radar_reductions", "radar_brakes", "min_danger_time_s"))  # stats()

    def __init__(self, params: DangerTimeParams, ctx=None, *, enforce: bool = True):
        self.p = params
        self.dt = ctx.step_s if ctx is not None else None
        self.enforce = enforce
        self.level: dict[str, int] = {}
        self.counts = {"radar_warnings": 0, "radar_reductions": 0, "radar_brakes": 0}
        self.min_td = math.inf

    def apply(self, v_des: np.ndarray, det, ego_width: np.ndarray, speed: np.ndarray, dt_s: float):
        """Desired velocities (E,2) m/s of ``det.ego_ids`` -> limited ones; speed (E,) current m/s."""
        p = self.p
        v_des = np.asarray(v_des, float).reshape(-1, 2)
        td, vc, gap = danger_time(det, ego_width, p.path_margin_m)
        lvl = levels(td, vc, p, gap)
        if len(td):
            self.min_td = min(self.min_td, float(td.min()))
        prev = np.array([self.level.get(v, NONE) for v in det.ego_ids], dtype=int)
        # hysteresis: full braking, once triggered, holds until the danger has passed (no chattering
        # between braking and releasing as the harder-than-planned braking lengthens t_d)
        hold = (prev == BRAKE) & ((td <= p.warning_s) | (gap <= 2.0 * p.standstill_gap_m))
        lvl = np.where(hold, BRAKE, lvl)
        self.counts["radar_warnings"] += int(((lvl >= WARNING) & (prev < WARNING)).sum())
        self.counts["radar_reductions"] += int(((lvl >= REDUCE) & (prev < REDUCE)).sum())
        self.counts["radar_brakes"] += int(((lvl >= BRAKE) & (prev < BRAKE)).sum())
        self.level = dict(zip(det.ego_ids, lvl.tolist()))
        s_des = np.hypot(v_des[:, 0], v_des[:, 1])
        cap = np.where(lvl == REDUCE, np.maximum(np.abs(speed) - p.reduce_decel_mps2 * dt_s, 0.0), np.inf)
        cap = np.where(lvl == BRAKE, 0.0, cap)
        scale = np.where(s_des > cap, cap / np.maximum(s_des, 1e-12), 1.0)
        return v_des * scale[:, None], lvl

    def add_ego(self, task) -> None:
        pass

    def remove_ego(self, vid: str) -> None:
        pass

    def filter(self, obs, command: np.ndarray) -> np.ndarray:
        snap = obs.snapshot
        limited, _ = self.apply(command, obs.scans[0], snap.width[obs.ego_rows], obs.ego_speed, self.dt)
        return limited if self.enforce else command

    def stats(self) -> dict:
        return {**self.counts, "min_danger_time_s": self.min_td if math.isfinite(self.min_td) else None}
