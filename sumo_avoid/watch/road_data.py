"""The road of a run as plain data for drawing (the HTML viewer, the video): lanes (centre line, width,
kind from their permissions), junction outlines, pedestrian crossings, read from the net with sumolib
(:class:`sumo_avoid.road.network.Road`); coordinates rounded to 0.1 m."""
from __future__ import annotations

import numpy as np

from sumo_avoid.plots.street import lane_kind
from sumo_avoid.road.network import Road


def _pts(a) -> list:
    return np.round(np.asarray(a, float)[:, :2], 1).tolist()


def road_data(net_file) -> dict:
    """{"lanes": [{"shape", "width", "kind"}], "junctions": [outline], "crossings": [{"shape", "width"}],
    "bounds": [xmin, ymin, xmax, ymax]}; empty lists without a net."""
    if net_file is None:
        return {"lanes": [], "junctions": [], "crossings": [], "bounds": None}
    road = Road.from_net_file(str(net_file))
    el = road.elements
    lanes = [{"shape": _pts(ln.shape), "width": round(ln.width_m, 2), "kind": lane_kind(ln.allow) or "road",
              "internal": ln.function == "internal"}
             for ln in el.lanes.values() if ln.function in ("", "internal") and len(ln.shape) >= 2]
    junctions = [_pts(j.shape) for j in el.junctions.values() if len(j.shape) >= 3]
    crossings = [{"shape": _pts(c.shape), "width": round(c.width_m, 2)} for c in el.crossings.values()
                 if len(c.shape) >= 2]
    walking = [_pts(w.shape) for w in el.walking_areas.values() if len(w.shape) >= 3]
    pts = [p for ln in lanes for p in ln["shape"]] + [p for j in junctions for p in j]
    bounds = None
    if pts:
        a = np.asarray(pts)
        bounds = [*a.min(axis=0).round(1).tolist(), *a.max(axis=0).round(1).tolist()]
    return {"lanes": lanes, "junctions": junctions, "crossings": crossings, "walking": walking, "bounds": bounds,
            "signals": signal_bars(road.right_of_way.net)}


def signal_bars(net) -> list:
    """Where each traffic-light link shows its state: ``[tls, link index, [x, y], [x, y]]``, a bar across
    the end of its incoming lane (the lane's links side by side, as sumo-gui draws them)."""
    by_lane: dict = {}
    for tls in net.getTrafficLights():
        for lane_in, _, index in tls.getConnections():
            if lane_in.getEdge().getFunction():  # a walking area's link: its crossing shows no bar
                continue
            by_lane.setdefault(lane_in, []).append((tls.getID(), int(index)))
    out = []
    for lane, links in by_lane.items():
        shape = np.asarray(lane.getShape(), float)[:, :2]
        if len(shape) < 2:
            continue
        end, d = shape[-1], shape[-1] - shape[-2]
        d = d / (np.linalg.norm(d) or 1.0)
        left = np.array([-d[1], d[0]])
        w = lane.getWidth()
        links = sorted(set(links), key=lambda tl: -tl[1])  # SUMO's link order runs right to left
        for k, (tls, index) in enumerate(links):
            a = end + left * (-w / 2 + w * k / len(links))
            b = end + left * (-w / 2 + w * (k + 1) / len(links))
            out.append([tls, index, np.round(a, 2).tolist(), np.round(b, 2).tolist()])
    return out
