"""Traffic rules as a layer (SPEC §5): any controller's command is limited so that the ego stops
for signals and keeps the speed the road ahead allows (``"traffic"`` in ``ego.layers``, there by
default; parameters in ``[layers.traffic]``). An ``ego.layers`` without it switches it off.

Per ego and step, with s the arc length of the ego's front bumper projected on its route path
(:class:`~sumo_avoid.core.types.EgoTask`: path, junction links, lane speed limits):

* **Signals.** For every signalised link ahead within ``lookahead_m`` (its state from the
  snapshot's ``signals``, index ``link_index``): 'r' / 'u' (red, red-yellow) -> stop; 'y' -> stop
  when the stop is comfortable, v^2 / (2 b_comf) <= distance to the line, decided once at the onset
  of the yellow (no flip-flop while braking) and else go on; 'G' / 'g' / 'o' / 'O' -> go, 'g' and
  'o' subject to right of way. A stop caps the speed at the braking curve
  sqrt(2 b_comf (d - margin)), d the distance of the front bumper to the stop line, so the ego
  stops ``stop_margin_m`` before the line.
* **Right of way.** At the next link ahead that must give way now (minor, permissive green,
  equal, roundabout entry, merge; :mod:`sumo_avoid.road.yielding`), the ego is held at its stop
  line by the same braking curve while a vehicle of a foe link with priority would reach the
  conflict point within the critical gap (plus a margin) after the ego reaches the line (a foe
  standing at its line for ``standing_foe_wait_s`` does not come: it holds the ego no longer); an ego
  that could stop before the line only braking harder than ``commit_decel_mps2`` goes on, and
  past the line it never stops for a foe (it clears the junction). A zipper merge is taken in
  turn (yielding.zipper_slot).
* **Clearing the junction.** On any link, also one with priority or green, the ego is held at its
  stop line the same way while a vehicle *moving* on the internal lanes of a link without priority
  that crosses or merges with its own (:attr:`~sumo_avoid.road.route.RouteLink.inside`) would reach
  the conflict point within that gap: it is in the junction and clears it first (SUMO's drivers
  treat it as a link leader). SUMO's vehicles enter when they see no SUMO-driven foe coming, and an
  ego standing at its line is none; one standing inside (waiting at its internal stop for the ego)
  does not hold it.
* **Crossing lanes of its own edge.** On any link the ego is held the same way while a vehicle of an
  open link from another lane of its own edge whose internal lanes cross its own (though the junction
  logic makes neither give way: :attr:`~sumo_avoid.road.route.RouteLink.crossers`, joined junctions)
  would reach the crossing within that gap, counted from its stop line too: SUMO lets both go at once
  and its drivers do not look for the ego there. Other egos are left out (each would wait for the other).
* **Junction box.** Before the nearest link ahead the ego is held at its stop line while a vehicle stands
  in the strip it would sweep through the junction, or the exit lacks room for it (SUMO's drivers do not
  enter a junction they could not leave; :mod:`sumo_avoid.safety.junction_box`).
* **Wide exits.** Where a turn is too tight for the car and its drivable line swings into the
  oncoming lane of the exit edge, the ego is held at its stop line until that lane is clear for
  the time it takes to make the turn (:mod:`sumo_avoid.safety.wide_turns`), on any link.
* **Narrow streets.** Before a stretch of its route where its lanes and the oncoming lane are together
  too narrow for it and an oncoming car to pass, the ego is held the same way while such a car is on
  it or arrives before the ego is through (:mod:`sumo_avoid.safety.narrow_streets`).
* **Stop signs.** At a link whose state is 's' (stop) or 'w' (all-way stop) the ego is held by
  the braking curve until it has stood (slower than ``stop_speed_mps``) with its front within
  ``stop_zone_m`` of its stop position; then it only gives way as above.
* **Speed for the road ahead.** v <= sqrt(v_i^2 + 2 b_comf (s_i - s)) for every lane piece i
  starting within ``lookahead_m`` at s_i with speed limit v_i x ``speed_factor`` (SUMO's
  speedFactor idea; 1 by default): the legal limits of the route's normal lanes, the one before a
  junction running on through it. A junction's internal lanes carry netconvert's turning speeds, no
  legal limit; they count only with ``turn_speeds`` (the controllers keep their own curve speed, and
  a cap in a junction shifted APF-SA's timing there enough to leave it stalled after being passed:
  left_turn, seed 1). ``speed_limits = false`` keeps no limit.

The command (desired velocity, m/s) keeps its direction; only its length is capped -- except while
the ego is held at a signal or a crossing below ``HELD_MPS``: then it points along the route path at
the ego's front, so the ego waits lined up with its lane instead of standing askew, half turned into
the junction (where its rear blocks the next lane and its corner the sidewalk). At a yield line it
keeps the controller's direction: there it waits for a gap, and a car lined up straight needs longer
to turn into it than the gap acceptance allows for (generated rand03, seed 5: rear-ended after a left
turn taken from the straight stance). The stop
line works as a virtual obstacle that no controller can drive through; SPEC §5 hands it to the
controller as one, which a potential-field controller would also steer around (the departure is
deliberate: a stop line is not something to swerve past). Counters: ``rules_signal_stops``
(episodes of an ego held by a signal), ``rules_yields`` (episodes of an ego giving way, one per
ego and line), ``rules_speed_caps`` (steps where the road speed capped the command).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sumo_avoid.core.geometry import near_any
from sumo_avoid.road.crossings import stands_on_crossing
from sumo_avoid.road.polyline import polyline_point_at, polyline_track
from sumo_avoid.road.regulation import RED, STOP_SIGNS, RulesParams, legal_limits, limit_index
from sumo_avoid.core.types import EgoTask, Keys
from sumo_avoid.safety.crossing_rule import CrossingRule
from sumo_avoid.safety.junction_box import box_cap, junction_exits
from sumo_avoid.safety.narrow_streets import narrow_cap, narrow_stretches
from sumo_avoid.safety.wide_turns import oncoming_first, wide_exits
from sumo_avoid.road.yielding import (
    STAND_MPS,
    can_give_way,
    clearing_arrivals,
    critical_gap_s,
    ego_time_to_line,
    foe_arrivals,
    link_state,
    rows_by_lane,
    yields,
    zipper_slot,
)

STOP, GO = "stop", "go"

HELD_MPS = 2.0  # held at a line below this speed, the ego waits lined up with its lane, m/s


def _brake_to(d_m: float, p: RulesParams) -> float:
    """The speed from which the ego stops ``stop_margin_m`` before a line ``d_m`` ahead braking at b_comf."""
    return math.sqrt(2.0 * p.comfort_decel_mps2 * max(d_m - p.stop_margin_m, 0.0))


def _direction(path, s_m: float) -> np.ndarray:
    """(2,) unit direction of the route path at arc length ``s_m`` (over the next metre)."""
    d = polyline_point_at(path, s_m + 1.0) - polyline_point_at(path, s_m)
    return d / max(float(np.hypot(d[0], d[1])), 1e-12)


@dataclass
class _Ego:
    task: EgoTask
    watch: bool  # anything on the route for this layer to enforce
    s_m: float = 0.0  # front bumper's arc length on task.path, followed step by step
    seen: bool = False
    yellow: dict = field(default_factory=dict)  # link position in task.links -> STOP | GO at the yellow's onset
    stopped: dict = field(default_factory=dict)  # link position of a stop sign where the ego has stood -> since when, s
    wide: dict = field(default_factory=dict)  # link position -> its wide exit into oncoming traffic (wide_turns)
    narrow: tuple = ()  # stretches too narrow to pass an oncoming car (narrow_streets)
    exits: tuple = ()  # per link, s where the route leaves its junction (junction_box)
    limits: np.ndarray | None = None  # the speed limits the layer keeps (kept_limits), once per ego


def signal_char(signals, link) -> str:
    """The state character of a signalised link ('' if not signalised or unknown)."""
    state = signals.get(link.tls, "") if link.tls else ""
    return state[link.link_index] if 0 <= link.link_index < len(state) else ""


def kept_limits(task: EgoTask, p: RulesParams) -> np.ndarray | None:
    """The rows of ``task.speed_limits`` the layer keeps (None: none): the normal lanes' legal limits, the one
    before a junction running on through it; a junction's internal lanes too with ``turn_speeds``."""
    return legal_limits(task.speed_limits, p.turn_speeds) if p.speed_limits else None


def road_speed_cap(task: EgoTask, s_m: float, p: RulesParams, limits=False) -> float:
    """Highest speed at arc length ``s_m`` from which every lane speed limit ahead (and the limit
    of the piece the ego is on) can be met braking at b_comf (``limits``: :func:`kept_limits`, if known)."""
    lim = kept_limits(task, p) if limits is False else limits
    if lim is None:
        return math.inf
    b = p.comfort_decel_mps2
    starts, v = lim[:, 0], lim[:, 1] * p.speed_factor
    here = limit_index(lim, s_m)
    ahead = (starts > s_m) & (starts <= s_m + p.lookahead_m)
    caps = np.sqrt(v[ahead] ** 2 + 2.0 * b * (starts[ahead] - s_m))
    return float(min(v[here], caps.min() if caps.size else math.inf))


class TrafficRulesLayer:
    """Traffic rules: stop for red and stoppable yellow lights, keep the road's speed ahead."""

    needs_scans = False
    monitor_when_scans = False
    stats_keys = Keys(("rules_signal_stops", "rules_speed_caps", "rules_yields", "rules_crossing_yields"))

    def __init__(self, params: RulesParams, ctx=None):
        self.p = params
        self._egos: dict[str, _Ego] = {}
        self._held: set[tuple[str, float]] = set()  # (ego, stop line s) where a signal held the ego
        self._caps = 0
        self._yields: set[tuple[str, float]] = set()  # (ego, stop line s) where the ego gave way
        self._allway = False  # an ego's route crosses an all-way stop: follow who stands since when
        self._foes = False  # an ego's route has a link with foes or a wide exit: follow who stands since when (for good)
        self._tls_since: dict[str, tuple[str, float]] = {}  # light id -> (its state, since when), s
        self._stand: dict[str, tuple] = {}  # vehicle id -> (start, end (nan: still)) of its last standing run, s
        self._turn_radius_m = float(getattr(ctx, "turn_radius_m", 0.0) or 0.0)  # 0: no drivable line, no wide exits
        self._crossings = CrossingRule(params)  # give way at pedestrian crossings, never stop on one
        self._crossing_yields: set[tuple[str, float]] = set()  # (ego, crossing entry s) where it held the ego
        self._watching: set[str] = set()  # egos with anything on their route to enforce

    def add_ego(self, task: EgoTask) -> None:
        wide = wide_exits(task, self._turn_radius_m)
        narrow = narrow_stretches(task) if task.lanes else ()
        limits = kept_limits(task, self.p)
        watch = (any(lk.tls or lk.foes or lk.inside or lk.crossers or lk.state in STOP_SIGNS or lk.crossings for lk in task.links) or bool(wide)
                 or bool(narrow) or limits is not None)
        exits = junction_exits(task) if task.lanes else ()
        self._egos[task.vid] = e = _Ego(task, watch or any(x == x for x in exits), wide=wide, narrow=narrow, exits=exits,
                                        limits=limits)
        if e.watch:
            self._watching.add(task.vid)
        self._allway |= any(lk.state == "w" and lk.foes for lk in task.links)
        self._foes |= any(lk.foes for lk in task.links) or bool(wide)

    def _track_standing(self, obs) -> None:
        """When each vehicle near an ego came to stand (for the order of arrival at all-way stops,
        and the foes that stand for good), and when each light last changed."""
        snap, t = obs.snapshot, obs.snapshot.time_s
        for tls, state in snap.signals.items():
            if self._tls_since.get(tls, ("",))[0] != state:
                self._tls_since[tls] = (state, t)
        # only those within lookahead_m of an ego, as the recording has them (output.record_radius_m,
        # 300 m) for the metric to judge the same: one farther away is forgotten, its runs unknown
        near = np.flatnonzero(near_any(snap.pos, snap.pos[obs.ego_rows], self.p.lookahead_m))
        known, stand = self._stand, {}
        for vid, v in zip([snap.ids[i] for i in near], snap.speed[near].tolist()):
            start, end = stand[vid] = known.get(vid, (math.nan, math.nan))
            if v < STAND_MPS and not (start == start and end != end):  # not standing yet: a new run starts
                stand[vid] = (t, math.nan)
            elif v >= STAND_MPS and start == start and end != end:  # standing until now: the run ends
                stand[vid] = (start, t)
        self._stand = stand

    def _standing_since(self, snap):
        """since(row, tls) for :func:`~sumo_avoid.road.yielding.stands_for_good`: when the row came to
        stand (now if it does not stand), or when light ``tls`` last changed if that is later."""
        t = snap.time_s

        def since(row: int, tls: str) -> float:
            start, end = self._stand.get(snap.ids[row], (t, t))
            light = self._tls_since.get(tls, ("", -math.inf))[1] if tls else -math.inf
            return max(start if end != end else t, light)
        return since

    def remove_ego(self, vid: str) -> None:
        self._egos.pop(vid, None)
        self._watching.discard(vid)

    def _signal_cap(self, e: _Ego, signals, v: float, length_m: float) -> tuple[float, float]:
        """(speed cap, s of the stop line that sets it) over the signals ahead."""
        p, cap, line = self.p, math.inf, -1.0
        for k, link in enumerate(e.task.links):
            d = link.s_stop_m - e.s_m - p.stop_margin_m
            if not link.tls or link.s_stop_m < e.s_m or d > p.lookahead_m:
                continue
            c = signal_char(signals, link)
            if c != "y":
                e.yellow.pop(k, None)
            if c == "y" and k not in e.yellow:
                # the law's test, the metric's: a comfortable stop before the line itself (d is to
                # the stop position, stop_margin_m before it; deciding on d would go on through yellows
                # the metric judges stoppable), and not standing on a crossing it is already on
                e.yellow[k] = STOP if (v * v / (2.0 * p.comfort_decel_mps2) <= d + p.stop_margin_m and not
                                       stands_on_crossing(e.task.links, e.s_m, link.s_stop_m, length_m)) else GO
            if c in RED or e.yellow.get(k) == STOP:
                # (the yellow's stop-or-go is judged at the stop line itself; the ego waits at the hold line)
                hold = link.hold_line_m(e.s_m, v, p.commit_decel_mps2, p.stop_margin_m)
                here = _brake_to(hold - e.s_m, p)
                if here < cap:
                    cap, line = here, link.s_stop_m
        return cap, line

    def _yield_cap(self, e: _Ego, snap, lanes, row: int, v: float) -> tuple[float, float]:
        """(speed cap, s of the yield line that sets it): stop before the next link that must give
        way while a foe with priority arrives within the critical gap (:mod:`.yielding`)."""
        p = self.p
        standing = (snap.time_s, p.standing_foe_wait_s, self._standing_since(snap))  # foes standing for good
        for k, link in enumerate(e.task.links):
            d = link.s_stop_m - e.s_m
            if d <= 0 and e.s_m >= link.yield_line_m:
                continue
            if d > p.lookahead_m:
                break
            late = v * v / (2.0 * p.commit_decel_mps2) > d
            d_hold = link.hold_line_m(e.s_m, v, p.commit_decel_mps2, p.stop_margin_m) - e.s_m  # where it waits
            if d > 0 and k not in e.stopped and link_state(snap.signals, link.tls, link.link_index, link.state) in STOP_SIGNS:
                if v < p.stop_speed_mps and d - p.stop_margin_m <= p.stop_zone_m:
                    e.stopped[k] = snap.time_s  # stood at the sign: from now on it only gives way
                elif not late:  # (at the line itself: the law's stop zone)
                    return _brake_to(d, p), link.s_stop_m
            wide = e.wide.get(k)
            if (wide is not None and not late and d > 0 and
                    oncoming_first(wide, e.s_m, lanes, snap.lane_pos, snap.speed,
                                   standing, row) < p.gap_margin_s):
                return _brake_to(d_hold, p), link.s_stop_m
            within = ego_time_to_line(d, v, p.stop_margin_m) + critical_gap_s(link, p) + p.gap_margin_s
            if link.inside and d > 0 and not late:  # who is in the junction clears it first, on any link
                clearing = clearing_arrivals(link.inside, lanes, snap.lane_pos, snap.speed, snap.length, {row})
                if min(clearing, default=math.inf) < within:
                    return _brake_to(d_hold, p), link.s_stop_m
            if link.crossers and d > 0 and not late:  # a link of its own edge crossing its path goes first, on any link
                found = foe_arrivals(link.crossers, snap.signals, lanes, snap.lane_pos, snap.speed, snap.length,
                                     set(np.flatnonzero(snap.is_ego).tolist()), None, standing)
                if min((a for a, _, _ in found), default=math.inf) < within:
                    return _brake_to(d_hold, p), link.s_stop_m
            if not link.foes:
                continue
            if link.yield_line_m > link.s_stop_m:  # a signalised turn waits at its internal junction
                d = d_hold = link.yield_line_m - e.s_m
                if d <= 0:
                    continue
                late = v * v / (2.0 * p.commit_decel_mps2) > d
            if not yields(link, snap.signals) or late:
                continue  # priority now, or too late to stop: go on
            order = (snap.time_s, e.stopped.get(k, math.inf),  # all-way stops: the ego first stood at its line then
                     lambda r: self._stand.get(snap.ids[r], (math.nan, math.nan)))
            found = foe_arrivals(link.foes, snap.signals, lanes, snap.lane_pos, snap.speed, snap.length, {row}, order,
                                 standing)
            arrivals = [a for a, _, _ in found]
            t_c, t_e = critical_gap_s(link, p), ego_time_to_line(d, v, p.stop_margin_m)
            if link.state == "Z":  # take turns: arrive in the first free slot (yielding.zipper_slot)
                give = can_give_way([x for _, _, x in found], [snap.speed[r] for _, r, _ in found], p.comfort_decel_mps2)
                t_slot = zipper_slot(t_e, arrivals, t_c + p.gap_margin_s, give)
                return (math.inf, -1.0) if t_slot <= t_e else (max(d - p.stop_margin_m, 0.0) / t_slot, link.s_stop_m)
            if min(arrivals, default=math.inf) < t_e + t_c + p.gap_margin_s:
                return _brake_to(d_hold, p), link.yield_line_m
            return math.inf, -1.0  # the nearest yield line ahead is clear: the ones after it wait their turn
        return math.inf, -1.0

    def filter(self, obs, command: np.ndarray) -> np.ndarray:
        snap = obs.snapshot
        out = np.array(command, dtype=float, copy=True)
        if not self._watching and not (self._allway or self._foes):  # nothing to enforce, nothing to track (an arena)
            return out
        lanes = None
        if self._allway or self._foes:
            self._track_standing(obs)
        for i, vid in enumerate(obs.ego_ids):
            e = self._egos.get(vid)
            if e is None or not e.watch:  # no signal on the route, no speed limits enforced: nothing to do
                continue
            r = obs.ego_rows[i]
            h = snap.heading[r]
            front = snap.pos[r] + 0.5 * snap.length[r] * np.array([math.cos(h), math.sin(h)])
            e.s_m = float(polyline_track(e.task.path, front, e.s_m if e.seen else None)[0])
            e.seen = True
            v = abs(float(obs.ego_speed[i]))
            sig, line = self._signal_cap(e, snap.signals, v, float(snap.length[r]))
            road = road_speed_cap(e.task, e.s_m, self.p, e.limits)
            if sig < v or sig < 0.5:  # one episode per ego and stop line, however often the cap binds
                self._held.add((vid, line))
            if lanes is None:
                lanes = rows_by_lane(snap.lane)
            give, yline = self._yield_cap(e, snap, lanes, int(r), v)
            if give < v or give < 0.5:
                self._yields.add((vid, yline))
            speed = math.hypot(out[i, 0], out[i, 1])
            cross, cline = self._crossings.cap(e.task, e.s_m, v, snap, int(r), float(snap.length[r]), float(snap.width[r]))
            if cross < v or cross < 0.5:
                self._crossing_yields.add((vid, cline))
            # a street too narrow to pass an oncoming car: wait before it (narrow_streets; an episode of giving way)
            narrow, nline = (narrow_cap(e.narrow, e.s_m, v, float(snap.width[r]), snap, lanes, self.p)
                             if e.narrow else (math.inf, -1.0))
            if narrow < v or narrow < 0.5:
                self._yields.add((vid, nline))
            # never stop inside a junction behind a vehicle that cannot leave (junction_box)
            box, bline = (box_cap(e.task, e.exits, e.s_m, v, speed, snap, int(r), float(snap.length[r]),
                                  float(snap.width[r]), self.p) if e.exits else (math.inf, -1.0))
            if box < v or box < 0.5:
                self._yields.add((vid, bline))
            cap = min(sig, road, give, cross, narrow, box)
            if speed > cap:
                self._caps += road < min(sig, give, cross, narrow, box)
                out[i] *= cap / speed
                if min(sig, cross, narrow, box) <= cap and cap < HELD_MPS:
                    # held at a line: wait lined up with the lane, not already turned into the junction
                    # (a car standing askew at its line blocks the next lane and its corner the sidewalk)
                    out[i] = cap * _direction(e.task.path, e.s_m)
        return out

    def stats(self) -> dict:
        return {"rules_signal_stops": len(self._held), "rules_speed_caps": self._caps,
                "rules_yields": len(self._yields), "rules_crossing_yields": len(self._crossing_yields)}
