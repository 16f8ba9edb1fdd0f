"""Streets too narrow for two cars to pass (SPEC §5, rules layer): wait for the oncoming car before them.

netconvert takes a lane's width from OpenStreetMap's tags or its type map, and on residential streets of
OSM districts it often draws one lane each way of 1.6 m (unseen Berlin Adlershof: 15 % of the length of
its two-way car streets, 198 edges). Two cars 1.8 m wide cannot pass there even on their lanes' centres.
SUMO's drivers do, overlapping (SUMO checks no lateral overlap between the lanes of two edges), and an
ego met one such car at 13.9 m/s. A driver waits before such a street while a car comes the other way.

A *narrow stretch* of the ego's route is a run of its normal edges (with the junctions between them)
where the ego's lanes and the oncoming lane beside them (:attr:`~sumo_avoid.road.route.LanePiece.opposite_m`)
are together narrower than two of the ego's width plus ``NARROW_MARGIN_M``. Before it, the ego is held
(the rules' braking curve to ``stop_margin_m`` before its start) while a vehicle too wide to pass it there
(its width + the ego's + the margin more than the room) is on the stretch's oncoming lanes, or on the
oncoming lanes of the ``ARRIVE_M`` beyond it arriving (at its speed, at least 1 m/s) before the ego, at
``CLEAR_MPS``, has driven through. An ego that cannot stop before it at ``commit_decel_mps2`` goes on;
one inside it goes on. People and cyclists pass a car there (a cyclist 0.65 m wide fits beside it).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

#: Two vehicles pass on a street only with this much room between them, m.
NARROW_MARGIN_M = 0.4
#: Oncoming vehicles this far beyond a narrow stretch's end are watched for, m.
ARRIVE_M = 60.0
#: The ego drives through a narrow stretch at least this fast (for the time it takes), m/s.
CLEAR_MPS = 5.0


@dataclass(frozen=True)
class NarrowStretch:
    s_start_m: float  # arc length on the ego's path where it starts, m
    s_end_m: float  # ... and ends, m
    room_m: float  # the least width of the ego's lanes and the oncoming lane together over it, m
    inside: tuple[tuple[str, float], ...]  # its oncoming lanes: (lane id, s on the path where that lane starts)
    beyond: tuple[tuple[str, float], ...]  # the oncoming lanes of the ARRIVE_M after it, the same way


def narrow_stretches(task) -> tuple[NarrowStretch, ...]:
    """The narrow stretches of an ego's route (module docstring)."""
    pieces = [p for p in task.lanes if not p.edge.startswith(":")]
    need = 2.0 * task.width_m + NARROW_MARGIN_M

    def room(p) -> float:
        own = sum(w for w, ok in zip(p.widths_m, p.usable()) if ok)
        return own + p.opposite_m if p.opposite_lane else math.inf

    out, k = [], 0
    while k < len(pieces):
        if room(pieces[k]) >= need:
            k += 1
            continue
        j = k
        while j + 1 < len(pieces) and room(pieces[j + 1]) < need:
            j += 1
        run = pieces[k:j + 1]
        after = [p for p in pieces[j + 1:] if p.opposite_lane and p.s_start_m < run[-1].s_end_m + ARRIVE_M]
        out.append(NarrowStretch(run[0].s_start_m, run[-1].s_end_m, min(room(p) for p in run), _starts(run), _starts(after)))
        k = j + 1
    return tuple(out)


def _starts(pieces) -> tuple[tuple[str, float], ...]:
    """(oncoming lane, s on the path where it starts) of these pieces. The oncoming lane of an edge runs
    against it and starts where the edge ends: at its last piece's end (where the path blends from one lane
    to another, an edge has two pieces, the first ending mid-edge)."""
    end: dict[str, float] = {}
    for p in pieces:
        end[p.opposite_lane] = max(end.get(p.opposite_lane, -math.inf), p.s_end_m)
    return tuple(end.items())


def narrow_cap(stretches, s_front_m: float, v_mps: float, width_m: float, snap, lanes: dict, p) -> tuple[float, float]:
    """(speed cap, s of the stretch's start that sets it) before the next narrow stretch ahead; (inf, -1)
    when none holds the ego. ``lanes``: lane id -> snapshot rows (yielding.rows_by_lane)."""
    for st in stretches:
        d = st.s_start_m - s_front_m
        if d <= 0.0:
            continue  # inside it (or past): go on
        if d > p.lookahead_m or v_mps * v_mps / (2.0 * p.commit_decel_mps2) > d:
            return math.inf, -1.0  # too far to matter yet, or too late to stop before it
        t_clear = (st.s_end_m - s_front_m) / CLEAR_MPS
        wide = lambda r: width_m + float(snap.width[r]) + NARROW_MARGIN_M > st.room_m  # noqa: E731
        if any(wide(r) and not snap.is_person[r] for lane, _ in st.inside for r in lanes.get(lane, ())):
            return math.sqrt(2.0 * p.comfort_decel_mps2 * max(d - p.stop_margin_m, 0.0)), st.s_start_m
        for lane, s_lane_start in st.beyond:
            for r in lanes.get(lane, ()):
                to_go = s_lane_start - float(snap.lane_pos[r]) - st.s_end_m  # its front to the stretch's end, m
                if wide(r) and not snap.is_person[r] and 0.0 <= to_go <= ARRIVE_M and \
                        to_go / max(float(snap.speed[r]), 1.0) < t_clear:
                    return math.sqrt(2.0 * p.comfort_decel_mps2 * max(d - p.stop_margin_m, 0.0)), st.s_start_m
        return math.inf, -1.0
    return math.inf, -1.0
