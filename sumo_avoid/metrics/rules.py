"""Traffic-rule metrics from the recording (SPEC §5 "Metrics"), whatever the rules layer did (a
run without ``"traffic"`` in ``ego.layers`` is measured the same way, against the same
``[layers.traffic]`` parameters).

``red_light_violations``: the ego's front bumper crosses a stop line (between two recorded steps)
while its link shows 'r' / 'u' at the earlier step, or 'y' when, at the onset of that yellow, the
ego could have stopped comfortably (v^2 / (2 b_comf) <= distance to the line, b_comf of the
scenario's ``[layers.traffic]``) and lawfully (not standing on a crossing it was already on:
:func:`~sumo_avoid.road.crossings.stands_on_crossing`). Details per crossing in ``signal_crossings`` (ego, tls, link, time, state).

``yield_violations``: the ego's front bumper crosses the stop line of a link that must give way at
that moment (:mod:`sumo_avoid.road.yielding`) while a recorded vehicle of a foe link with
priority arrives at its conflict point within the critical gap t_c of the ego's movement
(``[layers.traffic]`` critical_gap_s / critical_gap_left_s / zipper_headway_s; SUMO's lane positions from the
recording).
Details per crossing of a yielding link in ``yield_crossings`` (ego, junction, time, state, the
first foe and its arrival time, s).

A foe that has stood still at its line for ``standing_foe_wait_s`` (its light unchanged meanwhile)
is no foe, as for the layer (road.yielding.stands_for_good); its standing counts from its first
recorded step (the recording keeps vehicles within ``output.record_radius_m`` of an ego, 300 m; the
layer follows those within ``lookahead_m``, 250 m, so it never gives up on a foe sooner than this).

At an all-way stop, first come first served: a foe standing at its line that came to stand after
the ego did is no foe, the others arrive as from a standing start (safety.yielding).

``stop_sign_violations``: the ego's front crosses the line of a stop sign ('s' / 'w') without
having stood (slower than ``[layers.traffic]`` stop_speed_mps) within stop_margin_m + stop_zone_m before it;
``stop_crossings`` per crossing.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.road.polyline import polyline_track
from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.rollout.result import RunResult
from sumo_avoid.road.crossings import stands_on_crossing
from sumo_avoid.road.regulation import RED, STOP_SIGNS
from sumo_avoid.road.yielding import (
    STAND_MPS,
    can_give_way,
    critical_gap_s,
    first_crossing,
    foe_arrival,
    link_state,
    rows_by_lane,
    stand_run,
    yields,
)


def _state_at(sig, tls: str, t: float) -> tuple[str, float]:
    """(state string, time it began) of light ``tls`` at time ``t``."""
    rows = sig[(sig["tls"] == tls) & (sig["time_s"] <= t + 1e-9)]
    if rows.empty:
        return "", -np.inf
    return rows["state"].iloc[-1], float(rows["time_s"].iloc[-1])


def _signals_at(sig, t: float) -> dict[str, str]:
    """Every light's state string at time ``t``."""
    if sig is None or sig.empty:
        return {}
    rows = sig[sig["time_s"] <= t + 1e-9]
    return dict(zip(rows["tls"], rows["state"]))  # later rows win


def _ego_tracks(run: RunResult, want):
    """(ego id, task, its recorded rows, front bumper s along the route path) for the egos whose
    task has a link ``want(link)`` is true for."""
    tasks = {vid: task for vid, task in run.tasks.items() if any(want(lk) for lk in task.links)}
    if not tasks:
        return
    traj = run.traj[run.traj["is_ego"]]
    rows = traj.groupby("id", sort=False).indices  # each ego's row positions, in table order
    for vid, task in tasks.items():
        ego = traj.iloc[rows.get(vid, [])]
        if len(ego) < 2:
            continue
        h = ego["heading"].to_numpy()
        front = ego[["x", "y"]].to_numpy() + 0.5 * ego["length"].to_numpy()[:, None] * np.column_stack([np.cos(h), np.sin(h)])
        yield vid, task, ego, polyline_track(task.path, front)


def signal_crossings(run: RunResult) -> list[dict]:
    sig = run.signals
    if sig is None or sig.empty or not run.tasks:
        return []
    b = run.scenario.table("layers.traffic").comfort_decel_mps2
    out = []
    for vid, task, ego, s in _ego_tracks(run, lambda lk: bool(lk.tls)):
        t, v = ego["time_s"].to_numpy(), ego["speed"].to_numpy()
        for lk in (lk for lk in task.links if lk.tls):
            k = first_crossing(s, lk.s_stop_m)
            if k < 0:
                continue
            state, since = _state_at(sig, lk.tls, t[k])
            c = state[lk.link_index] if 0 <= lk.link_index < len(state) else ""
            violation = c in RED
            if c == "y":
                j = int(np.clip(np.searchsorted(t, since), 0, k))
                violation = (v[j] ** 2 / (2.0 * b) <= lk.s_stop_m - s[j] and
                             not stands_on_crossing(task.links, s[j], lk.s_stop_m, float(ego["length"].iloc[j])))
            out.append({"ego": vid, "tls": lk.tls, "link_index": lk.link_index, "time_s": float(t[k + 1]),
                        "state": c, "violation": bool(violation)})
    return out


def yield_crossings(run: RunResult) -> list[dict]:
    if not run.tasks or "lane" not in run.traj:
        return []
    p = run.scenario.table("layers.traffic")
    traj = run.traj
    out = []
    for vid, task, ego, s in _ego_tracks(run, lambda lk: bool(lk.foes)):
        steps, t = ego["step"].to_numpy(), ego["time_s"].to_numpy()
        for lk in (lk for lk in task.links if lk.foes):
            k = first_crossing(s, lk.yield_line_m)  # a signalised turn gives way at its internal junction
            signals = _signals_at(run.signals, t[k]) if k >= 0 else {}
            if k < 0 or not yields(lk, signals):
                continue
            now = traj[traj["step"] == steps[k]]
            ids = now["id"].to_numpy()
            speed = now["speed"].to_numpy(float)
            # a zipper foe that could still stop comfortably lets the ego in (safety.yielding)
            skip = None if lk.state != "Z" else (lambda t_f, r, x: bool(can_give_way(x, speed[r], p.comfort_decel_mps2)))
            # all-way stop: first come, first served, as the rules layer takes it (yielding.waits_its_turn)
            order = None
            if any(f.state == "w" for f in lk.foes):
                v_e = np.abs(ego["speed"].to_numpy(float)[:k + 1])
                at = np.flatnonzero((v_e < p.stop_speed_mps) & (lk.s_stop_m - s[:k + 1] - p.stop_margin_m <= p.stop_zone_m))
                before = traj[traj["step"] <= steps[k]]

                def history(r, before=before, ids=ids):
                    h = before[before["id"] == ids[r]]
                    return stand_run(h["time_s"].to_numpy(), h["speed"].to_numpy(float))
                order = (float(t[k]), float(t[at[0]]) if len(at) else np.inf, history)
            standing = (float(t[k]), p.standing_foe_wait_s, _standing_since(run, traj, steps[k], float(t[k]), ids, speed))
            t_f, who = foe_arrival(lk.foes, signals, rows_by_lane(now["lane"].fillna("").to_numpy()), now["lane_pos"].to_numpy(float),
                                   speed, now["length"].to_numpy(float), set(np.flatnonzero(ids == vid).tolist()), skip,
                                   order, standing)
            t_c = critical_gap_s(lk, p)
            out.append({"ego": vid, "junction": lk.junction, "time_s": float(t[k + 1]),
                        "state": link_state(signals, lk.tls, lk.link_index, lk.state),
                        "foe": str(ids[who]) if who >= 0 else "", "foe_arrival_s": None if who < 0 else round(t_f, 3),
                        "violation": bool(t_f < t_c)})
    return out


def _standing_since(run: RunResult, traj, step: int, t: float, ids, speed):
    """since(row, tls) of the rows recorded at ``step`` (time ``t``; their ``ids``, ``speed``), for
    yielding.stands_for_good: when the row came to stand (by the recording up to then; ``t`` when it
    moves), or when light ``tls`` last changed if that is later."""
    def since(r: int, tls: str) -> float:
        start = t
        if speed[r] < STAND_MPS:
            h = traj[(traj["step"] <= step) & (traj["id"] == ids[r])]
            start = stand_run(h["time_s"].to_numpy(), h["speed"].to_numpy(float))[0]
        light = _state_at(run.signals, tls, t)[1] if tls and run.signals is not None else -np.inf
        return max(start, light)
    return since


def stop_crossings(run: RunResult) -> list[dict]:
    """Crossings of a stop sign's line ('s' / 'w' at that moment): a violation unless the ego stood
    (slower than stop_speed_mps) with its front within stop_margin_m + stop_zone_m before the line."""
    if not run.tasks:
        return []
    p = run.scenario.table("layers.traffic")
    out = []
    for vid, task, ego, s in _ego_tracks(run, lambda lk: lk.state in STOP_SIGNS or bool(lk.tls)):
        t, v = ego["time_s"].to_numpy(), ego["speed"].to_numpy()
        for lk in task.links:
            k = first_crossing(s, lk.s_stop_m)
            if k < 0:
                continue
            c = link_state(_signals_at(run.signals, t[k]), lk.tls, lk.link_index, lk.state)
            if c not in STOP_SIGNS:
                continue
            near = (s[: k + 1] >= lk.s_stop_m - p.stop_margin_m - p.stop_zone_m)
            stood = bool(np.any(np.abs(v[: k + 1][near]) < p.stop_speed_mps))
            out.append({"ego": vid, "junction": lk.junction, "time_s": float(t[k + 1]), "state": c,
                        "violation": not stood})
    return out


class RuleViolations(Metric):
    """Red lights, yields and stop signs the egos ran, with every crossing judged."""

    keys = Keys(("red_light_violations", "yield_violations", "stop_sign_violations"),
                nested=("signal_crossings", "yield_crossings", "stop_crossings"))

    def compute(self, run: RunResult) -> dict:
        crossings = signal_crossings(run)
        yielding = yield_crossings(run)
        stops = stop_crossings(run)
        return {"red_light_violations": sum(c["violation"] for c in crossings),
                "signal_crossings": crossings,
                "yield_violations": sum(c["violation"] for c in yielding), "yield_crossings": yielding,
                "stop_sign_violations": sum(c["violation"] for c in stops), "stop_crossings": stops}
