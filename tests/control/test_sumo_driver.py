"""``controller = "sumo"``: SUMO's own driver as the baseline, on real libsumo and real nets. The ego
stays SUMO's (its speed and lane-change modes as SUMO set them, never faster than SUMO allows it),
stands at a red light's line until green, reaches its goal, and is scored like any ego."""
from __future__ import annotations

import libsumo
import numpy as np
import pytest
from conftest import SCENARIOS

from sumo_avoid.road.polyline import polyline_track
from sumo_avoid.runs import outputs
from sumo_avoid.runs.declared import metric_keys
from sumo_avoid.runs.runner import run
from sumo_avoid.scenario import spec as scenario

SUMO_SPEED_MODE, SUMO_LANE_CHANGE_MODE = 31, 1621  # SUMO's defaults: every check on, its own lane changes


class Watch:
    """Reads the ego from libsumo itself each step (a callback: it changes nothing)."""

    def __init__(self, vid: str):
        self.vid, self.rows = vid, []

    def on_step(self, snap, n_steps):
        if self.vid in libsumo.vehicle.getIDList():
            v = libsumo.vehicle
            self.rows.append((snap.time_s, v.getSpeed(self.vid), v.getAllowedSpeed(self.vid),
                              v.getSpeedMode(self.vid), v.getLaneChangeMode(self.vid)))

    def on_end(self):
        pass


def red_stands(res, vid: str, within_m: float = 10.0) -> list[tuple[str, float]]:
    """(light, time) of each recorded step at which ``vid`` stood (< 0.1 m/s) with its front bumper at
    most ``within_m`` before the stop line of a signalised link on its route while that link showed red."""
    task, sig = res.tasks[vid], res.signals
    ego = res.traj[res.traj["id"] == vid]
    h = ego["heading"].to_numpy()
    front = ego[["x", "y"]].to_numpy() + 0.5 * ego["length"].to_numpy()[:, None] * np.column_stack([np.cos(h), np.sin(h)])
    s, t, v = polyline_track(task.path, front), ego["time_s"].to_numpy(), ego["speed"].to_numpy()
    out = []
    for lk in (lk for lk in task.links if lk.tls):
        states = sig[sig["tls"] == lk.tls]
        for k in np.flatnonzero((v < 0.1) & (lk.s_stop_m - s >= 0) & (lk.s_stop_m - s <= within_m)):
            now = states[states["time_s"] <= t[k] + 1e-9]
            if len(now) and now["state"].iloc[-1][lk.link_index] in "rR":
                out.append((lk.tls, float(t[k])))
    return out


def test_sumo_drives_the_ego_through_six_signals_stops_at_red_and_is_scored_like_any_ego():
    scn = scenario.load(SCENARIOS / "roads" / "grid_static.toml", ["output.plots=false"], controller="sumo", seed=1)
    watch = Watch("ego")
    res = run(scn, callbacks=[watch])
    m = outputs.run_metrics(res)
    rows = np.array(watch.rows)
    assert len(rows) > 500
    # SUMO's driver in charge: its modes untouched, never faster than SUMO allows it on its lane
    assert set(rows[:, 3]) == {SUMO_SPEED_MODE} and set(rows[:, 4]) == {SUMO_LANE_CHANGE_MODE}
    assert np.all(rows[:, 1] <= rows[:, 2] + 1e-9) and rows[:, 1].max() > 10.0
    ego = res.traj[res.traj["id"] == "ego"]
    assert ego["is_ego"].all() and ego["speed"].max() <= 20.0  # its vType's maxSpeed
    # red: it stands at the line (seconds of it), and crosses every line on green
    stands = red_stands(res, "ego")
    assert len(stands) >= 20, stands
    assert m["red_light_violations"] == 0
    assert len(m["signal_crossings"]) == 6 and {c["state"] for c in m["signal_crossings"]} <= set("gG")
    assert all(c["time_s"] > max(t for tls, t in stands if tls == c["tls"]) for c in m["signal_crossings"]
               if any(tls == c["tls"] for tls, _ in stands))
    assert m["goal_reached"] is True and m["time_to_goal_s"] > 0
    # scored with every metric a driven ego gets (no layer runs, so no rules_* counters)
    assert set(m) == metric_keys(scn).names
    for key in ("collisions", "sumo_collisions", "sumo_ego_collisions", "yield_violations", "stop_sign_violations",
                "crossing_violations", "forbidden_lane_m", "wrong_way_m", "off_road_m", "phi_wall", "min_gap_m",
                "max_abs_jerk_mps3", "max_lat_accel_mps2", "min_ttc_s", "min_ttc2d_s", "path_length_m"):
        assert m[key] is not None, key
    assert m["controller"] == "sumo" and not any(k.startswith(("rules_", "sa_")) for k in m)


def test_the_same_scenario_and_seed_gives_the_same_sumo_driven_run():
    out = []
    for _ in range(2):
        scn = scenario.load(SCENARIOS / "left_turn.toml", ["output.plots=false"], controller="sumo", seed=2)
        res = run(scn)
        out.append((res.traj[res.traj["is_ego"]][["time_s", "x", "y", "speed"]].to_numpy(), res.steps))
    assert out[0][1] == out[1][1] and np.array_equal(out[0][0], out[1][0])


@pytest.mark.parametrize("controller", ["sumo", "apf_sa"])
def test_sumo_stays_in_charge_only_with_the_sumo_controller(controller):
    """The check above is not vacuous: a driven ego gets speed mode 32 and lane-change mode 0 when it
    is taken over (the step after SUMO inserted it: the first row is read before)."""
    scn = scenario.load(SCENARIOS / "left_turn.toml", ["sim.duration_s=5"], controller=controller)
    watch = Watch("ego")
    run(scn, callbacks=[watch])
    modes = {(int(r[3]), int(r[4])) for r in watch.rows[1:]}
    assert modes == ({(SUMO_SPEED_MODE, SUMO_LANE_CHANGE_MODE)} if controller == "sumo" else {(32, 0)})


def test_sumo_reaches_the_end_of_its_route_on_its_own_lane_and_a_point_goal_only_at_the_point():
    """SUMO's driver is told its route, no lane to end on: overtaking's goal is the route's end, on the
    reference path's lane, and SUMO's driver arrives on another (its centre never within 5 m of the
    point); it reached its goal when SUMO took it out there. A point goal is reached only at the point."""
    res, m = _run("overtaking", [])
    ego = res.traj[res.traj["id"] == "ego"]
    last = ego.iloc[-1]
    gap = np.hypot(ego["x"] - res.goals["ego"][0], ego["y"] - res.goals["ego"][1])
    assert gap.min() > scenario.load(SCENARIOS / "overtaking.toml").spec.ego.goal_tolerance_m
    assert res.arrivals == {"ego": last["time_s"]} and last["x"] > 1490.0  # SUMO arrived it at 1500 m
    assert m["goal_reached"] is True and m["time_to_goal_s"] == pytest.approx(last["time_s"] - ego["time_s"].iloc[0])
    far_lane = [1490.0, float(last["y"]) + 10.5]  # three lanes over, 10 m before the end
    res, m = _run("overtaking", [f"ego.goal={far_lane}"])
    assert res.arrivals == {} and m["goal_reached"] is False and m["time_to_goal_s"] is None


def _run(name: str, overrides: list[str]):
    scn = scenario.load(SCENARIOS / f"{name}.toml", ["output.plots=false", *overrides], controller="sumo", seed=1)
    res = run(scn)
    return res, outputs.run_metrics(res)
