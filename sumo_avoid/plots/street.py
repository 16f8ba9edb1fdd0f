"""The street's people and their places on a trajectory figure: sidewalks, bike lanes, bus and tram
lanes (from the net's lane permissions, :attr:`sumo_avoid.road.network.Road.elements`), pedestrian
crossings (zebra-striped), and the persons' tracks (each a thin line, a dot where it was last seen)."""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon as MplPolygon
from shapely.geometry import LineString

#: lane kind -> (fill colour, legend label)
KINDS = {"sidewalk": ("#d9cdb8", "sidewalk"), "bike": ("#d98c7a", "bike lane"), "bus": ("#e8c95a", "bus / tram lane")}
PERSON = "#7a2bd1"


def lane_kind(allow: frozenset) -> str | None:
    """'sidewalk' (pedestrians only), 'bike' (bicycles, no cars), 'bus' (buses or trams, no cars), else None."""
    if not allow or "passenger" in allow:
        return None
    if allow <= {"pedestrian", "wheelchair"}:
        return "sidewalk"
    if "bicycle" in allow:
        return "bike"
    if allow & {"bus", "tram", "coach", "rail_urban"}:
        return "bus"
    return None


def _strip(shape: np.ndarray, width_m: float):
    if len(shape) < 2 or LineString(shape).length <= 1e-9:
        return None
    poly = LineString(shape).buffer(0.5 * width_m, cap_style="flat", join_style="mitre", mitre_limit=3.0)
    return None if poly.is_empty or poly.geom_type != "Polygon" else np.asarray(poly.exterior.coords)


def draw_street(ax, road) -> list:
    """Special lanes and crossings; returns legend handles for what was drawn."""
    el = getattr(road, "elements", None)
    if el is None:
        return []
    seen = set()
    for ln in el.lanes.values():
        kind = lane_kind(ln.allow) if ln.function == "" else None
        ring = _strip(ln.shape[:, :2], ln.width_m) if kind else None
        if ring is not None:
            ax.add_patch(MplPolygon(ring, closed=True, facecolor=KINDS[kind][0], edgecolor="none", zorder=0.5))
            seen.add(kind)
    for c in el.crossings.values():
        ring = _strip(c.shape, c.width_m)
        if ring is not None:
            ax.add_patch(MplPolygon(ring, closed=True, facecolor="white", edgecolor="#555555", hatch="||",
                                    lw=0.4, zorder=0.6))
            seen.add("crossing")
    handles = [MplPolygon([[0, 0]], facecolor=KINDS[k][0], label=KINDS[k][1]) for k in KINDS if k in seen]
    if "crossing" in seen:
        handles.append(MplPolygon([[0, 0]], facecolor="white", edgecolor="#555555", hatch="||", label="crossing"))
    return handles


def draw_persons(ax, persons) -> list:
    """Each person's track and last position; returns a legend handle (none without persons)."""
    if persons is None or len(persons) == 0:
        return []
    for _, g in persons.sort_values(["id", "step"]).groupby("id", sort=False):
        ax.plot(g["x"].to_numpy(), g["y"].to_numpy(), color=PERSON, lw=0.6, alpha=0.6, zorder=3)
        ax.plot(g["x"].iloc[-1], g["y"].iloc[-1], "o", ms=2.5, color=PERSON, zorder=3)
    n = persons["id"].nunique()
    return [Line2D([], [], color=PERSON, lw=0.8, marker="o", ms=3, label=f"persons ({n})")]
