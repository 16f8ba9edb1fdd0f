"""Whether the vehicle standing ahead of an ego is queued (APF-SA's escapes wait for a queue, not for a
blocked lane): pure geometry in the ego's route frame (s along its path, d across).

A queue is a chain of vehicles standing (the first) or creeping (the others, slower than :data:`CREEP_MPS`) in the
ego's lane one behind the other -- each at most
:data:`CHAIN_GAP_M` bumper to bumper behind the next -- whose first stands within ``reach_m`` of a
stop line of the ego's path (a junction link's, or the path's end, where it leaves its last edge). It
moves when its junction lets it: drivers wait in it, they do not change lanes to pass it (bologna_bus_lane,
truth: braking behind a car waiting at the end of edge 46, the ego started an escape into the next lane,
stood across the two and was clipped by five passing cars). A van parked there is also "queued"; the
controller escapes past it once it has stood behind it for its patience (``queue_patience_s``).
"""
from __future__ import annotations

import numpy as np

CHAIN_GAP_M = 8.0  # a standing vehicle at most this far (bumper to bumper) behind the next is queued behind it, m
STAND_MPS = 0.5  # slower than this a vehicle stands, m/s
#: Ahead of the first (standing) vehicle, one slower than this still belongs to the queue, m/s: a queue moving off
#: from its line is still a queue (lyon_unseen, truth, seed 1, car74: the cars ahead of a cyclist it stood behind
#: crept off at 0.3-2.3 m/s, the chain ended at the first of them, and the ego escaped into a lane that ended 30 m
#: on, passed the queue and stood across two lanes with its nose in a 2.5 m gap)
CREEP_MPS = 2.5
LANE_HALF_M = 1.6  # a vehicle whose centre is this close across to the ego's is in its lane, m


def _in_lane_ahead(sc):
    """(centre s (O,), half length (O,), indices of the vehicles in the ego's lane reaching past its front)."""
    s, half = sc.o_pos[:, 0], 0.5 * np.asarray(sc.o_length, float)
    return s, half, np.flatnonzero((np.abs(sc.o_pos[:, 1] - sc.d) < LANE_HALF_M) & (s + half > sc.s + 0.5 * sc.length))


def queued_ahead(sc, stops_s, reach_m: float) -> bool:
    """Is the nearest vehicle ahead of the ego in its lane standing at the back of a queue whose first
    vehicle stands within ``reach_m`` of one of the stop lines ``stops_s`` (arc lengths on the path)?
    ``sc`` a :class:`~sumo_avoid.control.road_view.FrenetScene`."""
    if not len(sc.o_pos):
        return False
    s, half, mine = _in_lane_ahead(sc)
    if not len(mine):
        return False
    mine = mine[np.argsort(s[mine])]
    if np.hypot(*sc.o_vel[mine[0]]) >= STAND_MPS:
        return False  # the nearest one ahead moves: not waiting in a queue
    head = mine[0]
    for k in mine[1:]:
        if np.hypot(*sc.o_vel[k]) >= CREEP_MPS or (s[k] - half[k]) - (s[head] + half[head]) > CHAIN_GAP_M:
            break
        head = k
    head_front = s[head] + half[head]
    stops = np.asarray(stops_s, float)
    return bool(np.any((stops >= head_front - half[head]) & (stops - head_front <= reach_m)))


def waits_in_queue(sc, task, path_length_m: float, stood_s: float, reach_m: float, patience_s: float) -> bool:
    """An APF-SA ego trapped behind a queue (:func:`queued_ahead`; the stop lines of ``task.links`` and
    its path's end at ``path_length_m``) waits in it until it has stood ``patience_s`` (``stood_s`` so far)."""
    if stood_s >= patience_s:
        return False
    return queued_ahead(sc, [lk.s_stop_m for lk in task.links] + [path_length_m], reach_m)


def chain_end_s(sc) -> float:
    """Arc length of the front of the last vehicle in the chain ahead of the ego in its lane (moving or
    not, each at most :data:`CHAIN_GAP_M` bumper to bumper behind the next, the first that close to the
    ego's front); the ego's front when nothing is that close."""
    end = sc.s + 0.5 * sc.length
    if not len(sc.o_pos):
        return end
    s, half, mine = _in_lane_ahead(sc)
    for k in mine[np.argsort(s[mine] - half[mine])]:
        if s[k] - half[k] - end > CHAIN_GAP_M:
            break
        end = max(end, float(s[k] + half[k]))
    return end


def lane_runs_past(view, sc, offset_m: float) -> bool:
    """Does a car at ``offset_m`` (d) stay within the ego's corridor from where it is until a car length and
    :data:`CHAIN_GAP_M` beyond the end of the chain of vehicles ahead of it in its lane (:func:`chain_end_s`)?
    An escape into a lane that leaves the route's corridor before that only leads back into the same
    traffic (lyon_unseen, truth, seed 2, car74: in a queue moving off at 2-5 m/s towards a light 36 m on,
    it escaped into the next lane, which the route leaves at the junction, drove up it at 9.5 m/s, met
    the red and cut back into the queue, now standing, in a 3 m gap: contact).

    Where the path ends (the goal) before that point, a moving ego has no lane past the chain: its lane change
    would end where it must stop, not straight in the next lane (bologna_bus_lane, truth, seed 3: braking at
    4.5 m/s behind a car stopping at the red light at the end of its route, 10 m ahead, it escaped towards the
    free lane beside it, stood there 34 degrees askew and a passing car clipped it). Standing, it may (it backs up
    for the room first, ``ApfSaController._make_room``); a queue there holds it for its patience first."""
    s_end = chain_end_s(sc) + sc.length + CHAIN_GAP_M
    if s_end > view.length_m and float(np.hypot(*sc.vel)) >= STAND_MPS:
        return False
    s_end = min(s_end, view.length_m)
    s = np.arange(sc.s, s_end + 1.0, 1.0)
    lo, hi = view.corridor(s)
    half = 0.5 * sc.width
    return bool(np.all((lo + half <= offset_m) & (offset_m <= hi - half)))
