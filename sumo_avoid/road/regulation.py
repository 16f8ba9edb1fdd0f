"""The rules of the road as the plug-in judges them (SPEC §5): which signal states are red, which
links are stop signs, and the parameters of the traffic rules -- comfortable braking, critical gaps,
stop-sign standing -- shared by the traffic-rules layer (``safety/traffic.py``, which obeys them) and
the rule metrics (``metrics/rules.py``, which measure them from the recording, also in runs
without the layer)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.config import field_doc

RED = frozenset("ru")


def legal_limits(speed_limits, turn_speeds: bool = False):
    """The rows of a route's ``speed_limits`` ((K, 2 or 3): s where a lane piece starts, its limit, 1 on an internal
    lane) that are limits to keep, or None: the normal lanes' legal limits, the one before a junction running on
    through it; a junction's internal lanes too with ``turn_speeds`` (netconvert's turning speeds, no legal limit)."""
    lim = speed_limits
    if lim is None or len(lim) == 0:
        return None
    if lim.shape[1] > 2 and not turn_speeds:
        lim = lim[lim[:, 2] == 0.0]
    return lim if len(lim) else None


def limit_index(limits, s_m: float) -> int:
    """Row of ``limits`` (:func:`legal_limits`) in force at arc length ``s_m`` (the first before the route's start)."""
    return max(0, int(np.searchsorted(limits[:, 0], s_m, side="right")) - 1)
STOP_SIGNS = frozenset("sw")  # stop sign, all-way stop: stand at the line, then give way


@dataclass(frozen=True)
class RulesParams:
    comfort_decel_mps2: float = field_doc(3.0, positive=True, doc="b_comf: comfortable braking for signals "
                                                                   "and the road ahead, m/s^2 (SPEC §5)")
    stop_margin_m: float = field_doc(1.0, doc="stop the front bumper this far before a stop line, m")
    speed_limits: bool = field_doc(True, doc="keep the legal speed limits of the route's lanes (normal lanes, x "
                                              "speed_factor; false: none)")
    speed_factor: float = field_doc(1.0, positive=True, doc="lane speed limit x this = highest speed")
    turn_speeds: bool = field_doc(False, doc="also keep the speeds of junctions' internal lanes (netconvert's turning "
                                             "speeds, no legal limit; the controllers keep their own curve speed)")
    lookahead_m: float = field_doc(250.0, positive=True, doc="signals and speed limits this far ahead count, m")
    critical_gap_s: float = field_doc(4.5, positive=True, doc="t_c: a foe with priority must arrive at the conflict "
                                                               "point at least this long after the ego reaches the "
                                                               "line (straight, right, merges; s)")
    critical_gap_left_s: float = field_doc(5.0, positive=True, doc="t_c of left turns and U-turns, s")
    gap_margin_s: float = field_doc(0.5, doc="the layer accepts a gap only this much longer than t_c (foes may "
                                             "speed up; the metric judges against t_c), s")
    commit_decel_mps2: float = field_doc(6.0, positive=True, doc="an ego that could stop before a yield line only "
                                                                  "braking harder than this goes on, m/s^2")
    stop_speed_mps: float = field_doc(0.1, positive=True, doc="at a stop sign ('s' / 'w' links) the ego stands "
                                                               "(slower than this) before it goes on, m/s")
    stop_zone_m: float = field_doc(3.0, positive=True, doc="... with its front at most this far before the stop "
                                                            "position (stop_margin_m before the line), m")
    crossing_gap_m: float = field_doc(10.0, doc="at a crossing the ego gives way to a person walking towards its "
                                              "path from at most this far (SUMO's jmCrossingGap default; a person "
                                              "past the path, or standing beside it, does not hold the ego), m")
    crossing_margin_m: float = field_doc(1.0, doc="... and to one within this much of the footprint's side as it "
                                                  "passes over the crossing, m")
    standing_foe_wait_s: float = field_doc(30.0, positive=True, doc="a foe with priority that has stood still at (or "
                                           "behind) its stop line this long, its light unchanged, no longer counts "
                                           "as arriving: the ego goes (SUMO's drivers go when such a foe does not "
                                           "come: --ignore-junction-blocker, jmIgnoreFoeProb with jmIgnoreFoeSpeed, "
                                           "impatience growing over --time-to-impatience), s")
    zipper_headway_s: float = field_doc(1.0, positive=True, doc="t_c of a zipper merge ('Z' links): the ego enters "
                                                                 "at least this long after and before the foes "
                                                                 "(accepted freeway-merge lead/lag gaps are ~1 s), s")
