"""The run viewer: one self-contained HTML file (no network access: the data as JSON and the script
inline) showing a run on its road: every vehicle's and person's footprint over time on a timeline
slider with play/pause and speed, the events as marks on the timeline that jump there, the ego's
radar detections (where the run logged them) and its recorded velocity as an overlay, the signals'
recorded states and the metrics.

Thinning (:func:`stride`): the page holds at most ``max_rows`` footprints, by default as many as fit
into ``MAX_BYTES`` (18 MB) beside the road's JSON at ``BYTES_PER_ROW`` (40: a footprint's seven numbers
take ~38 bytes); a run with more keeps every k-th recorded step (k the smallest that fits) and every
step of an event, so a long big-traffic run's page stays below ~20 MB.

The page exposes its state for tests and tools as ``window.viewerState`` and as JSON in
``<pre id="state">``: the shown time, frame, every footprint's corners and the pairs whose footprints
touch (separating-axis test, 5 cm tolerance). ``FILE.html#t=5.7`` opens it at 5.7 s (the slider is
moved as a user would move it)."""
from __future__ import annotations

import html
import json
import math

import numpy as np
import pandas as pd

from sumo_avoid.watch.events import events
from sumo_avoid.watch.recording import Recording
from sumo_avoid.watch.road_data import road_data
from sumo_avoid.watch.viewer_js import CSS, SCRIPT

MAX_BYTES = 18_000_000
BYTES_PER_ROW = 40
MIN_ROWS = 20_000  # a road too big for the budget still leaves this many footprints


def stride(n_rows: int, n_steps: int, max_rows: int) -> int:
    """Every how many recorded steps a frame is kept so that about ``max_rows`` footprints remain."""
    if n_rows <= max_rows or n_steps <= 1:
        return 1
    return int(math.ceil(n_rows / max_rows))


def _r(a, nd: int) -> list:
    return np.round(np.asarray(a, float), nd).tolist()


def page_data(rec: Recording, max_rows: int | None = None) -> dict:
    """The JSON the page draws from (see the module docstring for the thinning)."""
    tables = [rec.traj.assign(person=False)]
    if rec.persons is not None and len(rec.persons):
        tables.append(rec.persons.assign(person=True, is_ego=False))
    rows = pd.concat(tables, ignore_index=True)
    rows["t"] = rows["time_s"].round(6)
    times = np.array(sorted(rows["t"].unique()))
    evs = events(rec)
    road = road_data(rec.net_file)
    if max_rows is None:
        road_bytes = len(json.dumps(road, separators=(",", ":")))
        max_rows = max(MIN_ROWS, (MAX_BYTES - road_bytes) // BYTES_PER_ROW)
    k = stride(len(rows), len(times), max_rows)
    keep = set(times[::k].tolist()) | {times[-1]}
    for e in evs:  # the step of every event stays
        keep.add(float(times[min(np.searchsorted(times, e.time_s - 1e-9), len(times) - 1)]))
    kept = np.array(sorted(keep))
    rows = rows[rows["t"].isin(kept)]
    first = rows.drop_duplicates("id")
    ids = first["id"].astype(str).tolist()
    index = {v: i for i, v in enumerate(ids)}
    actors = [{"id": v, "ego": bool(r.is_ego), "person": bool(r.person), "length": round(float(r.length), 2),
               "width": round(float(r.width), 2)} for v, r in zip(ids, first.itertuples())]
    frame_of = {t: i for i, t in enumerate(kept.tolist())}
    frames = [[] for _ in kept]
    a = rows.assign(ai=rows["id"].astype(str).map(index), fi=rows["t"].map(frame_of))
    for fi, ai, x, y, h, v, vx, vy in zip(a["fi"], a["ai"], _r(a["x"], 2), _r(a["y"], 2), _r(a["heading"], 3),
                                          _r(a["speed"], 2), _r(a["vx"], 2), _r(a["vy"], 2)):
        frames[fi].extend((ai, x, y, h, v, vx, vy))
    return {"title": rec.title, "step_s": rec.step_s, "stride": k, "times": kept.tolist(), "actors": actors,
            "frames": frames, "road": road,
            "events": [{"t": e.time_s, "kind": e.kind, "label": e.label, "x": _fin(e.x_m), "y": _fin(e.y_m),
                        "ego": e.ego, "other": e.other} for e in evs],
            "detections": _detections(rec, kept), "signals": _signals(rec), "metrics": _scalars(rec.metrics),
            "goals": _goals(rec)}


def _fin(v):
    return None if v is None or not math.isfinite(v) else round(float(v), 2)


def _detections(rec: Recording, kept: np.ndarray) -> dict:
    """frame index -> [[x, y], ...] of the egos' radar detections at that frame (nearest kept frame)."""
    d = rec.detections
    if d is None or d.empty:
        return {}
    out: dict = {}
    fi = np.clip(np.searchsorted(kept, d["time_s"].to_numpy(float) - 1e-9), 0, len(kept) - 1)
    for f, x, y in zip(fi.tolist(), _r(d["x"], 1), _r(d["y"], 1)):
        out.setdefault(str(f), []).extend((x, y))
    return out


def _signals(rec: Recording) -> list:
    s = rec.signals
    return [] if s is None else [[round(float(t), 3), str(tls), str(st)] for t, tls, st in
                                 zip(s["time_s"], s["tls"], s["state"])]


def _goals(rec: Recording) -> list:
    p = rec.run_dir / "replay.json"
    try:
        goals = json.loads(p.read_text()).get("goals", {}) if p.is_file() else {}
    except (OSError, ValueError):
        goals = {}
    return [[k, round(float(v[0]), 2), round(float(v[1]), 2)] for k, v in goals.items() if len(v) == 2]


def _scalars(m: dict) -> list:
    return [[k, v if not isinstance(v, float) else (round(v, 4) if math.isfinite(v) else None)]
            for k, v in sorted(m.items()) if v is None or isinstance(v, (bool, int, float, str))]


def viewer_html(rec: Recording, max_rows: int | None = None) -> str:
    """The whole page, one string."""
    data = json.dumps(page_data(rec, max_rows), separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    title = html.escape(f"run viewer: {rec.title}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{title}</title><style>{CSS}</style></head>"
            f"<body><div id='top'><b>{title}</b> <span id='clock'></span></div>"
            "<div id='main'><canvas id='cv' width='1000' height='600'></canvas><div id='side'>"
            "<h3>now</h3><div id='now'></div><h3>events</h3><div id='evlist'></div>"
            "<h3>signals</h3><div id='sig'></div><h3>metrics</h3><div id='metrics'></div></div></div>"
            "<div id='bar'><button id='play'>play</button> <select id='speed'>"
            + "".join(f"<option value='{s}'{' selected' if s == 1 else ''}>{s}×</option>" for s in (0.25, 0.5, 1, 2, 4, 8, 16))
            + "</select> <label><input type='checkbox' id='follow' checked> follow ego</label>"
            "<div id='track'><input type='range' id='slider' min='0' value='0' step='1'><div id='marks'></div></div></div>"
            "<pre id='state' hidden></pre>"
            f"<script>window.RUN={data};</script><script>{SCRIPT}</script></body></html>\n")
