"""Passing a standing vehicle in the oncoming lane (APF-SA, issue 33): a van delivering in the only car
lane, a bike lane beside it, the oncoming lane busy now and then.

A trapped APF-SA ego (:mod:`.apf_sa`) searches its escape within its own direction's lanes; where they
offer none it may borrow the oncoming lane beside them (:attr:`~sumo_avoid.road.route.LanePiece.opposite_m`,
a lane its class may use) for a pass, as a driver does, when all of this holds:

* the ego stands, held behind what blocks it, which stands (slower than :data:`STAND_MPS`) in its strip
  within ``pass_look_m``, and has stood there for ``pass_wait_s`` (the ego has been held behind it that
  long): a delivery, a breakdown;
* it is no queue: nothing else stands in the ego's strip within ``pass_queue_gap_m`` beyond it, and no
  junction's stop line of the route lies within that distance of its front (a car waiting at a light
  or a junction is not passed);
* the oncoming lane is there for the whole pass, from a car length and ``pass_room_m`` (the room it
  backs up to) behind the ego to
  ``pass_return_m`` beyond the blocker's front (SUMO's nets: the edge running the other way between the
  same junctions; no junction inside the stretch);
* the oncoming lane is free for the pass: every vehicle the ego senses in it ahead or beside it (behind
  its rear too when it must back up first) reaches the point where the ego is back in its own lane
  no sooner than the time the ego needs to drive there plus ``pass_margin_s`` (:meth:`OncomingPass.need`:
  speeding up at ``pass_accel_mps2`` to its cruise speed until its rear is past the stretch, then back
  across, its left side over the centre line, at the field's ``max_lat_speed_mps``), and the ego sees far
  enough for a car at ``pass_oncoming_mps`` it cannot see yet (a radar sees the scenario's
  ``[sensors.radar] max_range_m``, ground truth everything: with the seed's 100 m radar a pass from standing,
  about 7 s and 50 m, is never certain against an unseen car at 16.7 m/s, which needs some 220 m). ``pass_accel_mps2`` is the ego's own, a little low: from standing 8 m behind the van of
  van_bike_lane APF-SA is back in its lane 7.0-7.1 s and 45-49 m later on every seed that passes, which
  :meth:`OncomingPass.need` puts at 7.1 s and 50.5 m. Until 2026-11-28 the check ended at the stretch's end,
  15-20 m short of that point, and assumed 1.5 m/s^2: oncoming cars passed the point 3.8 s after the ego at
  the least (seeds 3, 4, 7, 8), and 2.0 m/s^2 alone brought that to 0.3 s; now 6.8 s at the least (seeds 1-10).

While all of this but a free oncoming lane holds (:meth:`OncomingPass.candidate`), an ego that sees
behind it (ground truth or a rear radar) makes its room first: it backs up in its lane until
``pass_room_m`` is free ahead and stands there (``ApfSaController._wait_to_pass``), so the pass, once the
lane is free, needs only its own time, not the back-up's too (about 9 s less of free oncoming lane:
van_bike_lane with ground truth, 7 of 10 seeds pass instead of 4; 8 m rather than the escapes' 15 m: 7 m
less to drive in the oncoming lane);
it drives on as before once nothing stands ahead any more.

While it passes, the oncoming lane belongs to its corridor (``RoadView.passing``), so the escape search
and the field use it; until its front reaches the blocker's rear the carrot lies at most half that gap
ahead (:data:`PASS_CARROT_MIN_M` at least), so the car is out of its lane before it gets there (with the
carrot's usual 15 m it was not, stopped at the van's corner half in the oncoming lane, backed up and went
again without looking: seeds 7 and 8 touched oncoming cars). The pass ends when the ego's rear is past the stretch; it is called off while the
ego is still in its own lane (its centre within ``ABORT_D_M`` of the lane's) and an oncoming vehicle
would reach the stretch's end before it; once it has moved out it completes the pass (half in the
oncoming lane is the one place not to stop). Driving in the oncoming lane is
counted by ``wrong_way_m`` like any other.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.config import field_doc
from sumo_avoid.core.geometry import footprint_corners

STAND_MPS = 0.5  # a blocker slower than this stands, m/s
ABORT_D_M = 0.5  # a pass is called off only while the ego's centre is this close to its lane's centre, m
PASS_CARROT_MIN_M = 5.0  # moving out behind the blocker, the carrot lies at least this far ahead, m
BEHIND_M = 3.0  # an oncoming car's centre this far behind the ego's rear is past it (no back-up), m


@dataclass(frozen=True)
class PassParams:
    """The pass's keys, in ``[controllers.apf_sa]``."""

    pass_oncoming: bool = field_doc(True, doc="pass a standing vehicle in the oncoming lane when it is free "
                                              "(control/apf/oncoming_pass.py)")
    pass_wait_s: float = field_doc(8.0, doc="... after being held behind it this long, s")
    pass_look_m: float = field_doc(25.0, doc="... when it stands this close ahead, m")
    pass_queue_gap_m: float = field_doc(15.0, doc="... and nothing stands, nor is a stop line, within this of "
                                                  "its front (no queue), m")
    pass_room_m: float = field_doc(8.0, doc="waiting to pass, the ego stands (backs up to) this far behind it, m")
    pass_return_m: float = field_doc(8.0, doc="the pass ends this far beyond the blocker's front plus a car length, m")
    pass_accel_mps2: float = field_doc(2.0, positive=True, doc="the ego's speed-up assumed for the pass, m/s^2")
    pass_margin_s: float = field_doc(3.0, doc="oncoming vehicles reach the pass's end at least this long after "
                                              "the ego, s")
    pass_oncoming_mps: float = field_doc(16.7, doc="speed assumed for an oncoming vehicle the ego cannot see yet, m/s")


class OncomingPass:
    """Decides, per ego, when APF-SA borrows the oncoming lane (module doc); holds no state but the
    blocker's first sighting per ego."""

    def __init__(self, params: PassParams, reverse_speed_mps: float = 1.5, lat_speed_mps: float = 1.5):
        """``reverse_speed_mps``: how fast APF-SA backs up (to ``pass_room_m``) before it drives round a
        blocker it stands close behind; ``lat_speed_mps``: its speed across the road at most (the way
        back into its lane)."""
        self.p = params
        self.reverse_mps, self.lat_mps = reverse_speed_mps, lat_speed_mps
        self._behind: dict[str, tuple[float, float]] = {}  # vid -> (time first held, blocker's rear s)

    def forget(self, vid: str) -> None:
        self._behind.pop(vid, None)

    def blocker(self, sc) -> tuple[float, float] | None:
        """(rear s, front s) of the nearest vehicle standing in the ego's strip within ``pass_look_m``."""
        if not len(sc.o_pos):
            return None
        rel = footprint_corners(sc.o_pos, sc.o_heading, sc.o_length, sc.o_width) - sc.q
        half = 0.5 * sc.width + 0.3
        in_strip = (rel[..., 1].max(axis=1) >= -half) & (rel[..., 1].min(axis=1) <= half)
        ahead = in_strip & (rel[..., 0].min(axis=1) > 0.0) & (rel[..., 0].min(axis=1) < self.p.pass_look_m)
        standing = np.hypot(sc.o_vel[:, 0], sc.o_vel[:, 1]) < STAND_MPS
        k = np.flatnonzero(ahead)
        if not len(k):
            return None
        j = k[np.argmin(rel[k, :, 0].min(axis=1))]
        if not standing[j]:
            return None
        rear, front = sc.q[0] + rel[j, :, 0].min(), sc.q[0] + rel[j, :, 0].max()
        # a queue: something else stands in the strip just beyond it
        beyond = in_strip & standing & (rel[..., 0].min(axis=1) + sc.q[0] > front) & \
            (rel[..., 0].min(axis=1) + sc.q[0] < front + self.p.pass_queue_gap_m)
        return None if beyond.any() else (float(rear), float(front))

    def candidate(self, vid, view, sc, t: float, task) -> tuple | None:
        """(blocker's rear s, its front s, s_from, s_to) when the ego stands behind a vehicle it may pass
        (every condition of the module doc but a free oncoming lane), else None."""
        p = self.p
        if not p.pass_oncoming or view.lanes is None or np.hypot(*sc.vel) > 0.3:
            return None  # decided standing behind it (the time the pass needs is known then)
        b = self.blocker(sc)
        if b is None:
            self._behind.pop(vid, None)
            return None
        first = self._behind.get(vid)
        if first is None or abs(first[1] - b[0]) > 1.0:
            self._behind[vid] = (t, b[0])
            return None
        if t - first[0] < p.pass_wait_s:
            return None
        if any(b[1] - 1.0 <= lk.s_stop_m <= b[1] + p.pass_queue_gap_m for lk in task.links):
            return None  # it waits at a junction
        # from behind the room the ego backs up to when it stands close behind the blocker (apf_sa._make_room)
        s_from, s_to = sc.s - sc.length - p.pass_room_m, b[1] + sc.length + p.pass_return_m
        if float(view.lanes.opposite(np.linspace(s_from, s_to, 24)).min()) <= 0.0:
            return None
        return b[0], b[1], s_from, s_to

    def start(self, vid, view, sc, t: float, task, cruise_mps: float, sight_m: float, oncoming) -> tuple | None:
        """The stretch (s_from, s_to) to borrow the oncoming lane for now and the blocker's rear s, or None. ``oncoming(s_from,
        s_to_far)`` returns the (s, s_dot) of the vehicles sensed in the oncoming lane over that range."""
        p = self.p
        c = self.candidate(vid, view, sc, t, task)
        if c is None:
            return None
        b, (s_from, s_to) = c[:2], c[2:]
        # standing close behind it the ego first backs up to pass_room_m (apf_sa._make_room)
        back = max(p.pass_room_m - (b[0] - sc.s - 0.5 * sc.length), 0.0)
        s_end, t_pass = self.need(view, sc, s_to, cruise_mps, back)
        reach = s_end - sc.s + p.pass_oncoming_mps * (t_pass + p.pass_margin_s)
        if reach > sight_m:
            return None  # the lane may hold a car it cannot see yet
        # a car past the ego's rear drives away from it; one backing up meets those behind it too
        s_look = s_from if back > 0 else sc.s - 0.5 * sc.length - BEHIND_M
        if not self.clear(oncoming(s_look, sc.s + reach), s_end, t_pass):
            return None
        return s_from, s_to, b[0]

    def need(self, view, sc, s_to: float, cruise_mps: float, back_m: float = 0.0) -> tuple[float, float]:
        """(s_end, t): where the ego's centre is when it is back in its own lane (its left side over the
        centre line; the pass ends with its rear past ``s_to``, then it moves back across at
        ``lat_speed_mps``) and the time it needs to get there (backing up ``back_m`` first)."""
        v = float(np.hypot(*sc.vel))
        a = self.p.pass_accel_mps2
        v_end = min(max(cruise_mps, v), math.sqrt(v * v + 2.0 * a * max(s_to - sc.s + back_m, 0.0)))
        shift = 0.5 * (float(view.lanes.opposite([s_to])[0]) + sc.width)
        s_end = s_to + 0.5 * sc.length + v_end * shift / self.lat_mps
        t = (back_m / self.reverse_mps + 2.0 if back_m > 0 else 0.0) + self.time_to(s_end - sc.s + back_m, v, cruise_mps)
        return s_end, t

    def time_to(self, dist_m: float, v_mps: float, cruise_mps: float) -> float:
        """Time to drive ``dist_m`` from ``v_mps`` speeding up at ``pass_accel_mps2`` to ``cruise_mps``."""
        a, d = self.p.pass_accel_mps2, max(dist_m, 0.0)
        v_top = max(cruise_mps, v_mps)
        d_acc = (v_top * v_top - v_mps * v_mps) / (2.0 * a)
        if d <= d_acc:
            return (-v_mps + math.sqrt(v_mps * v_mps + 2.0 * a * d)) / a
        return (v_top - v_mps) / a + (d - d_acc) / max(v_top, 1e-6)

    def clear(self, vehicles, s_to: float, t_pass: float) -> bool:
        """No oncoming vehicle (s, s_dot) reaches ``s_to`` within ``t_pass`` + ``pass_margin_s``."""
        for s_o, v_o in vehicles:
            if s_o <= s_to:
                return False  # already in the stretch
            closing = max(-v_o, 0.1)
            if (s_o - s_to) / closing < t_pass + self.p.pass_margin_s:
                return False
        return True
