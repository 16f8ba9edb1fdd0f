"""Gap acceptance for a lane change, in one route frame (s along the road, d across it): whether a
car may move into a lane beside it. Shared by every road-going controller (the path's own lane
changes in :mod:`sumo_avoid.control.road_view`, the formation's in
:mod:`sumo_avoid.control.formation.lane_plan`). Pure numpy.
"""
from __future__ import annotations

import numpy as np

#: A vehicle overlapping a lane by more than this across the road is in it, m.
LANE_OVERLAP_M = 0.3
#: Lane change gap: this much clear road ahead of and behind the car at equal speeds, m ...
GAP_MIN_M = 3.0
#: ... plus, to a connected vehicle (a formation member: it knows the plan over V2V), the closing
#: speed times this, s;
GAP_HEADWAY_S = 1.5
#: ... plus, to any other vehicle, the secure gap of SUMO's Krauss model for the one behind: it reacts
#: after this, s, ...
GAP_REACT_S = 1.0
#: ... and both brake at this (SUMO's default for a passenger car), m/s^2.
GAP_DECEL_MPS2 = 4.5


def secure_gap_m(v_behind, v_ahead, react_s: float = GAP_REACT_S, decel_mps2: float = GAP_DECEL_MPS2):
    """Krauss's secure gap (elementwise, m): the room the vehicle behind (at ``v_behind``) needs to
    the one ahead (at ``v_ahead``) so that, reacting after ``react_s`` and both braking at
    ``decel_mps2``, it stops behind it: max(v_b tau + (v_b^2 - v_a^2) / 2b, 0)."""
    vb, va = np.maximum(np.asarray(v_behind, float), 0.0), np.maximum(np.asarray(v_ahead, float), 0.0)
    return np.maximum(vb * react_s + (vb * vb - va * va) / (2.0 * decel_mps2), 0.0)


def lane_change_length_m(shift_m: float, turn_radius_m: float) -> float:
    """The shortest distance along the road in which a car turning at most at ``turn_radius_m``
    moves ``shift_m`` across it and is straight again: two opposite arcs of angle a, across
    2R(1 - cos a) = shift, along 2R sin a (at shift >= 2R: 2R, the arcs' largest reach). 0 without a
    radius."""
    shift = abs(float(shift_m))
    if not turn_radius_m > 0.0 or shift == 0.0:
        return 0.0
    cos_a = max(1.0 - shift / (2.0 * turn_radius_m), 0.0)
    return 2.0 * turn_radius_m * float(np.sqrt(1.0 - cos_a * cos_a))


def in_band(o_d, o_wid, band: tuple[float, float]) -> np.ndarray:
    """(O,) which vehicles (centres at d = ``o_d``, widths ``o_wid``) overlap the lane across [band]
    by more than LANE_OVERLAP_M."""
    o_d, o_wid = np.asarray(o_d, float), np.asarray(o_wid, float)
    return (o_d + 0.5 * o_wid > band[0] + LANE_OVERLAP_M) & (o_d - 0.5 * o_wid < band[1] - LANE_OVERLAP_M)


def lane_blockers(s: float, speed: float, length: float, o_pos, o_len, o_wid, o_vs, band: tuple[float, float],
                  member=None, move_m: float = 0.0) -> np.ndarray:
    """(O,) the vehicles that keep a car at arc length s (its ``length``, ``speed`` along the road)
    from moving into the lane across [band] (d, m): those overlapping that band (:func:`in_band`)
    nearer, bumper to bumper, than GAP_MIN_M plus, for a connected vehicle (``member`` (O,) True;
    it knows the plan), GAP_HEADWAY_S x the closing speed, and for any other vehicle the secure gap
    (:func:`secure_gap_m`) of whichever of the two is behind: a car coming up fast from behind must
    be able to brake for the car that moved in, even if that one then brakes too. A vehicle ahead
    also needs the room the move itself takes (``move_m``, :func:`lane_change_length_m`) for the part
    of it the car closes on it (1 - its speed / the car's, at least 0): a car that starts a change
    towards a standing car it cannot finish before stops across the two lanes."""
    o_pos = np.asarray(o_pos, float).reshape(-1, 2)
    if not len(o_pos):
        return np.zeros(0, bool)
    o_vs = np.asarray(o_vs, float)
    member = np.zeros(len(o_pos), bool) if member is None else np.asarray(member, bool)
    inside = in_band(o_pos[:, 1], o_wid, band)
    ahead = o_pos[:, 0] >= s
    close = np.where(ahead, speed - o_vs, o_vs - speed)
    secure = np.where(ahead, secure_gap_m(speed, o_vs), secure_gap_m(o_vs, speed))
    closes = np.clip(1.0 - o_vs / max(speed, 0.1), 0.0, 1.0)
    room = (GAP_MIN_M + np.where(member, GAP_HEADWAY_S * np.maximum(close, 0.0), secure) + 0.5 * (length + o_len)
            + np.where(ahead, move_m * closes, 0.0))
    return inside & (np.abs(o_pos[:, 0] - s) < room)


def lane_is_free(s: float, speed: float, length: float, o_pos, o_len, o_wid, o_vs, band: tuple[float, float],
                 member=None, move_m: float = 0.0) -> bool:
    """Whether a car at arc length s may move into the lane across [band]: no :func:`lane_blockers`."""
    return not lane_blockers(s, speed, length, o_pos, o_len, o_wid, o_vs, band, member, move_m).any()
