"""A run replayed in sumo-gui on its own net: every recorded vehicle and person put where the
recording has it at each recorded step (TraCI's ``moveToXY``, exact position and heading; SUMO's
own driving and collision handling are off; persons are purple discs of their size, SUMO's
pedestrian models either ignoring ``moveToXY`` (nonInteracting) or failing on many moved persons
(striping)), the egos magenta and followed (the view centred on the first ego), a point of interest at
each event (time, what, with whom), the traffic lights set to their recorded states.

Why TraCI and not SUMO's fcd-replay device: the recording holds centres and math headings of every
road user and the exact steps, so the replay places each where it was without re-reading an FCD
file, needs no extra output during the run, and keeps persons, egos driven off their lanes and
signal states; libsumo has no GUI, so sumo-gui runs in its own process, driven over TraCI.

The window stays open on the last step until it is closed (the command returns then);
``--screenshot FILE --at S`` closes it at the end and saves the view at time S (with the view's bounds beside it,
``FILE.json``: x0, y0, x1, y1 in net metres, so a pixel maps to a net position)."""
from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import math
import pathlib
import subprocess
import time

import numpy as np
import pandas as pd
import sumo  # the eclipse-sumo wheel: sumo-gui
import traci  # sumo-gui's remote control, the release of libsumo and sumolib

from sumo_avoid.watch.events import events
from sumo_avoid.watch.recording import Recording

EGO_RGBA = (255, 0, 255, 255)
OTHER_RGBA = (60, 150, 60, 255)
PERSON_RGBA = (122, 43, 209, 255)
VIEW = "View #0"
SETTINGS = """<viewsettings><scheme name="sumo-avoid replay"><background backgroundColor="238,241,234"/>
<vehicles vehicleMode="0" vehicleQuality="2" minVehicleSize="1" vehicleExaggeration="1" showBlinker="0"/>
<pois poiExaggeration="1" poiName_show="0" poiType_show="1" poiType_size="40" poiType_color="200,0,0"/>
</scheme><delay value="{delay}"/></viewsettings>
"""


@dataclasses.dataclass(frozen=True)
class ReplaySpec:
    t_from_s: float | None = None
    t_to_s: float | None = None
    speed: float = 1.0  # recorded seconds per wall-clock second (the GUI's delay)
    screenshot: pathlib.Path | None = None
    screenshot_at_s: float | None = None
    view_m: float | None = 80.0  # width of the view that follows the first ego, m; None: sumo-gui's own view


def sumo_gui() -> str:
    return str(pathlib.Path(sumo.SUMO_HOME) / "bin" / "sumo-gui")


def front(row) -> tuple[float, float, float]:
    """SUMO's front-bumper position and compass angle (deg) of a recorded centre and math heading."""
    h = float(row.heading)
    return (float(row.x) + 0.5 * float(row.length) * math.cos(h), float(row.y) + 0.5 * float(row.length) * math.sin(h),
            (90.0 - math.degrees(h)) % 360.0)


def _edge(lane) -> str:
    return str(lane).rsplit("_", 1)[0] if isinstance(lane, str) and lane else ""


def _command(rec: Recording, begin_s: float, settings: pathlib.Path, quit_at_end: bool) -> list[str]:
    """sumo-gui's command line; without ``quit_at_end`` its window stays open on the last step until closed."""
    return [sumo_gui(), "-n", str(rec.net_file), "--step-length", str(rec.step_s), "--begin", f"{begin_s:.6f}",
            "--start", *(["--quit-on-end"] if quit_at_end else []), "--no-step-log", "--no-warnings",
            "--collision.action", "none",
            "--time-to-teleport", "-1", "--gui-settings-file", str(settings), "--window-size", "1100,760"]


def replay(rec: Recording, spec: ReplaySpec, work: pathlib.Path) -> dict:
    """Play the run in sumo-gui (a display is needed); returns {"steps", "screenshot", "bounds"}."""
    rows = rec.traj.assign(person=False)
    if rec.persons is not None and len(rec.persons):
        rows = pd.concat([rows, rec.persons.assign(person=True, is_ego=False)], ignore_index=True)
    times = np.array(rec.times_s)
    t0 = times[0] if spec.t_from_s is None else times[np.searchsorted(times, spec.t_from_s - 1e-9).clip(0, len(times) - 1)]
    t1 = times[-1] if spec.t_to_s is None else min(times[-1], spec.t_to_s)
    shown = times[(times >= t0 - 1e-9) & (times <= t1 + 1e-9)]
    delay_ms = max(0.0, 1000.0 * rec.step_s / spec.speed) if spec.speed > 0 else 0.0
    settings = work / "replay.settings.xml"
    settings.write_text(SETTINGS.format(delay=delay_ms))
    label = f"replay-{id(rec)}"
    with contextlib.redirect_stdout(io.StringIO()):  # TraCI prints "Retrying in 1 seconds" while sumo-gui starts
        traci.start(_command(rec, t0 - rec.step_s, settings, spec.screenshot is not None), label=label, stdout=subprocess.DEVNULL)
    con = traci.getConnection(label)
    out = {"steps": 0, "screenshot": None, "bounds": None}
    try:
        _setup(con, rec)
        present: dict = {}
        signals = rec.signals.sort_values("time_s") if rec.signals is not None else None
        if signals is not None:  # only the net's own (recordings before 2026-11-29 could hold a previous run's)
            signals = signals[signals["tls"].astype(str).isin(con.trafficlight.getIDList())]
        by_time = {round(t, 6): g for t, g in rows.groupby(rows["time_s"].round(6))}
        shot_t = None if spec.screenshot is None else shown[np.argmin(np.abs(shown - (spec.screenshot_at_s or t0)))]
        for t in shown:
            g = by_time.get(round(float(t), 6), rows.iloc[:0])
            present = _place(con, rec, g, present)
            if signals is not None:
                for tls, state in signals[signals["time_s"] <= t + 1e-9].groupby("tls")["state"].last().items():
                    con.trafficlight.setRedYellowGreenState(tls, state)
            ego = g[g["is_ego"].astype(bool)]
            if spec.view_m and len(ego):  # follow the first ego: a view_m wide window centred on it
                x, y, w = float(ego["x"].iloc[0]), float(ego["y"].iloc[0]), spec.view_m
                con.gui.setBoundary(VIEW, x - w / 2, y - w / 4, x + w / 2, y + w / 4)
            shoot = shot_t is not None and abs(t - shot_t) < 1e-9
            if shoot:  # saved at the end of the step that puts everyone at time t
                con.gui.screenshot(VIEW, str(spec.screenshot))
            con.simulationStep()
            out["steps"] += 1
            if shoot:
                (x0, y0), (x1, y1) = con.gui.getBoundary(VIEW)
                out["bounds"], out["screenshot"] = [x0, y0, x1, y1], str(spec.screenshot)
    finally:
        con.close()
    if out["screenshot"]:
        _wait_for(pathlib.Path(out["screenshot"]))
        pathlib.Path(str(out["screenshot"]) + ".json").write_text(json.dumps(
            {"time_s": float(shot_t), "bounds_m": out["bounds"]}) + "\n")
    return out


def _setup(con, rec: Recording) -> None:
    """A route to add vehicles on (positions come from moveToXY), the events' points of interest."""
    edges = [e for e in con.edge.getIDList() if not e.startswith(":")]
    con.route.add("replay_route", [edges[0]])
    for i, e in enumerate(events(rec)):
        if math.isfinite(e.x_m) and math.isfinite(e.y_m):
            colour = (224, 0, 0, 255) if e.kind == "collision" else (224, 168, 0, 255)
            con.poi.add(f"event{i}", e.x_m, e.y_m, colour, poiType=e.label, layer=100, width=3, height=3)


def _place(con, rec: Recording, g: pd.DataFrame, present: dict) -> dict:
    """Put every road user of one recorded step where it was; remove those no longer recorded.
    ``present``: id -> "person" or "vehicle" of those in the GUI now."""
    now = {str(r.id): ("person" if r.person else "vehicle") for r in g.itertuples(index=False)}
    for vid in present.keys() - now.keys():
        (con.poi if present[vid] == "person" else con.vehicle).remove(vid)
    for r in g.itertuples(index=False):
        vid = str(r.id)
        x, y, angle = front(r)
        if r.person:  # a disc (a point of interest) of the person's size where the recording has the person
            if vid not in present:
                con.poi.add(vid, float(r.x), float(r.y), PERSON_RGBA, poiType="", layer=50,
                            width=max(0.5, float(r.length)), height=max(0.5, float(r.length)))
            else:
                con.poi.setPosition(vid, float(r.x), float(r.y))
            continue
        if vid not in present:
            tid = f"rec_{vid}"
            con.vehicletype.copy("DEFAULT_VEHTYPE", tid)
            con.vehicletype.setLength(tid, float(r.length))
            con.vehicletype.setWidth(tid, float(r.width))
            con.vehicle.add(vid, "replay_route", typeID=tid, depart="now")
            con.vehicle.setSpeedMode(vid, 0)
            con.vehicle.setLaneChangeMode(vid, 0)
            con.vehicle.setColor(vid, EGO_RGBA if r.is_ego else OTHER_RGBA)
        con.vehicle.moveToXY(vid, _edge(r.lane), 0, x, y, angle, keepRoute=2)
        con.vehicle.setSpeed(vid, max(0.0, float(r.speed)))
    return now


def _wait_for(path: pathlib.Path, timeout_s: float = 10.0) -> None:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and not (path.is_file() and path.stat().st_size > 0):
        time.sleep(0.1)
