"""Static figures of a run: trajectories on the road, and stacked metric time series.

Rendering uses matplotlib's Agg canvas created inside each function (``Figure`` +
``FigureCanvasAgg``), so importing this module never selects a backend and pyplot's
global state is never touched.

Trajectory frame columns (one row per vehicle per recorded step):
``step, time_s, id, is_ego, x, y, vx, vy, speed, heading, length, width`` — centres and
math headings (rad, CCW from +x), as in :mod:`sumo_avoid.core.snapshot`.
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np
import shapely
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import PathPatch
from matplotlib.patches import Polygon as MplPolygon
from matplotlib.path import Path

from sumo_avoid.core import geometry
from sumo_avoid.plots.street import draw_persons, draw_street

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from sumo_avoid.road.network import Road

__all__ = ["draw_road", "footprint_corners", "plot_timeseries", "plot_trajectories", "track_xy"]

ROAD_FILL = "#a9a9a9"
OFFROAD_FILL = "#eef1ea"
MARKING = "#ffffff"
MEDIAN = "#f3d34a"
EGO_COLOURS = ["#0046c7", "#d6007a", "#ff7f0e", "#00875a", "#7a2bd1", "#8c564b"]
OTHER_COLOURS = ["#1b7a1b", "#8c564b", "#0e8a99", "#8a8a10", "#6a3d9a", "#505050"]
_NICE = [1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50]
ZOOM_HALF_M = 30.0  # the close-up of a turn or a collision shows 60 m x 60 m


def footprint_corners(x, y, heading, length, width) -> np.ndarray:
    """(N,4,2) rectangle corners from column arrays (see :func:`sumo_avoid.core.geometry.footprint_corners`)."""
    x, y, h, ln, w = (np.atleast_1d(np.asarray(v, float)) for v in (x, y, heading, length, width))
    return geometry.footprint_corners(np.column_stack([x, y]), h, ln, w)


def _new_figure(figsize):
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, out_png) -> str:
    out = os.fspath(out_png)
    parent = os.path.dirname(os.path.abspath(out))
    os.makedirs(parent, exist_ok=True)
    fig.savefig(out, dpi=150, bbox_inches="tight")
    return out


def _area_patch(geom, **kw):
    """PathPatch of a shapely (Multi)Polygon, holes included."""
    polys = getattr(geom, "geoms", [geom])
    verts, codes = [], []
    for poly in polys:
        if poly.is_empty:
            continue
        for ring in [poly.exterior, *poly.interiors]:
            xy = np.asarray(ring.coords)
            verts.append(xy)
            codes.append(np.r_[Path.MOVETO, np.full(len(xy) - 2, Path.LINETO), Path.CLOSEPOLY])
    if not verts:
        return None
    return PathPatch(Path(np.concatenate(verts), np.concatenate(codes).astype(np.uint8)), **kw)


def _collision_xy(collisions, traj):
    """(x, y, label) for every collision row; positions looked up in ``traj`` if absent."""
    out = []
    cols = set(collisions.columns)
    id_cols = [c for c in ("id", "ego_id", "id_a", "a", "vehicle", "veh_a") if c in cols]
    other_cols = [c for c in ("other_id", "id_b", "b", "other", "veh_b", "collider", "victim") if c in cols]
    for _, row in collisions.iterrows():
        t = row.get("time_s", np.nan)
        names = [str(row[c]) for c in (id_cols[:1] + other_cols[:1])]
        if "x" in cols and "y" in cols:
            x, y = float(row["x"]), float(row["y"])
        elif names:
            sub = traj[traj["id"].astype(str) == names[0]]
            if len(sub) == 0:
                continue
            key = "step" if "step" in cols and "step" in sub else "time_s"
            k = int(np.argmin(np.abs(sub[key].to_numpy(float) - float(row[key]))))
            x, y = float(sub["x"].iloc[k]), float(sub["y"].iloc[k])
            if not np.isfinite(t):
                t = float(sub["time_s"].iloc[k])
        else:
            continue
        label = " × ".join(names) if names else "collision"
        if np.isfinite(t):
            label += f" @ {t:.1f} s"
        out.append((x, y, label))
    return out


def _extent(traj, extra_pts, road):
    """Axis limits: everything drawn, widened to the road surface near it, plus a margin."""
    pts = [traj[["x", "y"]].to_numpy(float)] if len(traj) else []
    pts += [np.asarray(p, float).reshape(-1, 2) for p in extra_pts]
    pts = [p for p in pts if len(p)]
    allp = np.concatenate(pts) if pts else np.zeros((0, 2))
    allp = allp[np.all(np.isfinite(allp), axis=1)]
    if not len(allp):
        xmin, ymin, xmax, ymax = road.bounds
    else:
        (xmin, ymin), (xmax, ymax) = allp.min(axis=0), allp.max(axis=0)
        near = shapely.clip_by_rect(road.area, xmin - 8, ymin - 8, xmax + 8, ymax + 8)
        if not near.is_empty:  # show the full road width around the vehicles
            bx0, by0, bx1, by1 = near.bounds
            xmin, ymin, xmax, ymax = min(xmin, bx0), min(ymin, by0), max(xmax, bx1), max(ymax, by1)
    dx, dy = xmax - xmin, ymax - ymin
    mx = max(5.0, 0.03 * max(dx, dy)) if dx > 4 * dy else max(5.0, 0.05 * max(dx, dy))
    my = max(4.0, 0.08 * dy) if dx > 4 * dy else max(5.0, 0.05 * max(dx, dy))
    return xmin - mx, xmax + mx, ymin - my, ymax + my


def plot_trajectories(road: "Road", traj: "pd.DataFrame", out_png, *, collisions=None, goals=None,
                      title: str = "", obstacles=None, persons=None) -> str:
    """Bird's-eye figure of a run (see module docstring for ``traj`` columns); returns the path.

    ``goals``: {ego_id: (x, y)}; ``collisions``: rows with x, y (or an id column plus
    step/time_s to look the position up in ``traj``) and optionally time_s, other id;
    ``obstacles``: list of (K,2) polygons; ``persons``: their rows (as ``traj``), drawn as thin tracks,
    with sidewalks, bike and bus lanes and crossings (:mod:`sumo_avoid.plots.street`). Very elongated extents (e.g. a 1.5 km straight)
    are drawn on a wide figure with a stated vertical exaggeration so the lanes stay readable.
    """
    traj = traj.sort_values(["id", "step"] if "step" in traj else ["id", "time_s"])
    obstacles = [np.asarray(o, float).reshape(-1, 2) for o in (obstacles or [])]
    goals = {str(k): np.asarray(v, float).reshape(2) for k, v in (goals or {}).items()}
    coll = _collision_xy(collisions, traj) if collisions is not None and len(collisions) else []
    xmin, xmax, ymin, ymax = _extent(traj, list(goals.values()) + obstacles + [np.array([c[:2] for c in coll])],
                                     road)
    dx, dy = xmax - xmin, ymax - ymin

    exaggeration = 1
    if dx / dy > 4.0:  # wide strip: 16 in across, height so that the lanes stay visible
        fig_w, fig_h = 16.0, 4.5
        want = (fig_w - 1.5) / (fig_h - 1.6) * dy / dx  # data aspect that would fill the axes
        exaggeration = max([n for n in _NICE if n <= max(1.0, 1.0 / want)] or [1])
        if exaggeration == 1:
            fig_h = max(2.5, 1.6 + (fig_w - 1.5) * dy / dx)
    elif dy / dx > 4.0:
        fig_w, fig_h = 6.0, 12.0
    else:
        fig_w = 10.0
        fig_h = float(np.clip(fig_w * dy / dx + 0.8, 4.0, 12.0))
    fig = _new_figure((fig_w, fig_h))
    ax = fig.add_subplot(1, 1, 1)
    is_ego = traj["is_ego"].astype(bool) if "is_ego" in traj else np.zeros(len(traj), bool)
    ego_ids = list(dict.fromkeys(traj.loc[is_ego, "id"].astype(str)))
    other_ids = list(dict.fromkeys(traj.loc[~is_ego, "id"].astype(str)))
    groups = {str(k): g for k, g in traj.groupby(traj["id"].astype(str), sort=False)}
    handles = _draw(ax, road, groups, ego_ids, other_ids, obstacles, goals, coll, persons=persons)
    wide = exaggeration > 1 or fig_w / fig_h > 3
    centre = None if wide else _zoom_centre(groups, ego_ids, coll)
    legend_loc = "best"
    if centre is not None and min(dx, dy) > 6 * ZOOM_HALF_M:  # only where the close-up is small against the view
        corners = _emptiest_corners(traj, xmin, xmax, ymin, ymax)
        inset = ax.inset_axes([*_CORNERS[corners[0]], 0.42, 0.42])
        _draw(inset, road, groups, ego_ids, other_ids, obstacles, goals, coll, labels=False, persons=persons)
        cx, cy = centre
        inset.set_xlim(cx - ZOOM_HALF_M, cx + ZOOM_HALF_M)
        inset.set_ylim(cy - ZOOM_HALF_M, cy + ZOOM_HALF_M)
        inset.set_aspect(1.0)
        inset.tick_params(labelsize=7)
        inset.set_title(f"close-up, {2 * ZOOM_HALF_M:.0f} m across", fontsize=8)
        ax.indicate_inset_zoom(inset, edgecolor="#333333")
        legend_loc = corners[1]
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect(float(exaggeration))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]" if exaggeration == 1 else f"y [m]  (vertical ×{exaggeration})")
    ax.grid(True, color="white", alpha=0.35, lw=0.5)
    if title:
        ax.set_title(title)
    if wide:
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.28), ncol=min(len(handles), 6),
                  fontsize=8, frameon=False)
    elif fig_h / fig_w > 1.5:  # a narrow tall road fills the axes' width: the legend goes beside it
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False)
    else:
        ax.legend(handles=handles, loc=legend_loc, fontsize=8, framealpha=0.9)
    return _save(fig, out_png)


def _draw(ax, road, groups, ego_ids, other_ids, obstacles, goals, coll, labels: bool = True, persons=None) -> list:
    """Everything of a trajectory figure on one axes (the main view, or the close-up); returns the
    legend handles."""
    handles = draw_road(ax, road) + draw_persons(ax, persons)

    for ob in obstacles:
        ax.add_patch(MplPolygon(ob, closed=True, facecolor="#222222", edgecolor="black", zorder=3))
    if obstacles:
        handles.append(MplPolygon([[0, 0]], facecolor="#222222", label="obstacle"))


    def outline(g, rows, colour, lw, z, ls="-"):
        c = footprint_corners(g["x"].to_numpy()[rows], g["y"].to_numpy()[rows], g["heading"].to_numpy()[rows],
                              g["length"].to_numpy()[rows], g["width"].to_numpy()[rows])
        for poly in c:
            ax.add_patch(MplPolygon(poly, closed=True, fill=False, edgecolor=colour, lw=lw, ls=ls, zorder=z))

    for i, vid in enumerate(other_ids):
        g = groups[vid]
        col = OTHER_COLOURS[i % len(OTHER_COLOURS)]
        ax.plot(*track_xy(g), color=col, lw=1.3, alpha=0.9, zorder=2, gid=f"track:{vid}")
        outline(g, [0, len(g) - 1] if len(g) > 1 else [0], col, 1.1, 2)
    if other_ids:
        handles.append(Line2D([], [], color=OTHER_COLOURS[0], lw=1, label=f"other vehicles ({len(other_ids)})"))

    for i, vid in enumerate(ego_ids):
        g = groups[vid]
        col = EGO_COLOURS[i % len(EGO_COLOURS)]
        ax.plot(*track_xy(g), color=col, lw=2.6, zorder=5, solid_capstyle="round", gid=f"track:{vid}")
        t = g["time_s"].to_numpy(float)
        bucket = np.floor((t - t[0]) / 2.0 + 1e-9)
        rows = np.flatnonzero(np.r_[True, np.diff(bucket) > 0])
        rows = np.union1d(rows, [len(g) - 1])
        outline(g, rows, col, 1.1, 6)
        ax.plot(g["x"].iloc[0], g["y"].iloc[0], "o", ms=8, mfc="white", mec=col, mew=2, zorder=7)
        handles.append(Line2D([], [], color=col, lw=2.6, marker="o", mfc="white", label=f"{vid if vid.startswith('ego') else 'ego ' + vid} (outline / 2 s)"))
        if vid in goals:
            gx, gy = goals[vid]
            ax.plot(gx, gy, "*", ms=18, color=col, mec="black", mew=0.8, zorder=8)
    for gid, (gx, gy) in goals.items():
        if gid not in ego_ids:
            ax.plot(gx, gy, "*", ms=18, color="gold", mec="black", mew=0.8, zorder=8)
    if goals:
        handles.append(Line2D([], [], ls="", marker="*", ms=12, color="gold", mec="black", label="goal"))

    for x, y, label in coll:
        ax.plot(x, y, "x", ms=20, mew=4, color="#e00000", zorder=9)
        if labels:
            ax.annotate(label, (x, y), xytext=(8, 8), textcoords="offset points", color="#b00000", fontsize=9,
                        fontweight="bold", zorder=10, bbox=dict(boxstyle="round,pad=0.2", fc="white",
                                                                 ec="#e00000", alpha=0.85))
    if coll:
        handles.append(Line2D([], [], ls="", marker="x", ms=10, mew=3, color="#e00000",
                              label=f"collision ({len(coll)})"))

    return handles



def draw_road(ax, road) -> list:
    """The road on ``ax``: drivable area, lane lines, medians, sidewalks, special lanes and crossings;
    returns the legend handles (also the run video's background, :mod:`sumo_avoid.watch.video`)."""
    ax.set_facecolor(OFFROAD_FILL)

    patch = _area_patch(road.area, facecolor=ROAD_FILL, edgecolor="#6b6b6b", linewidth=0.8, zorder=0)
    if patch is not None:
        ax.add_patch(patch)
    for line in road.lane_lines("dashed"):
        ax.plot(line[:, 0], line[:, 1], color=MARKING, lw=0.8, ls=(0, (6, 6)), zorder=1)
    for line in road.lane_lines("edge"):
        ax.plot(line[:, 0], line[:, 1], color=MARKING, lw=1.2, zorder=1)
    any_median = False
    for line in road.lane_lines("median"):  # on a one-way road this is the left edge: keep it white
        edge = _on_boundary(road, line)
        any_median |= not edge
        ax.plot(line[:, 0], line[:, 1], color=MARKING if edge else MEDIAN, lw=1.4, zorder=1)

    handles = [Line2D([], [], color=ROAD_FILL, lw=6, label="drivable area"),
               Line2D([], [], color="#808080", lw=1, ls="--", label="lane line")]
    if any_median:
        handles.append(Line2D([], [], color=MEDIAN, lw=1.5, label="solid (no crossing)"))
    return handles + draw_street(ax, road)


def track_xy(g) -> tuple[np.ndarray, np.ndarray]:
    """x, y of one vehicle's rows (in step order) with a NaN between the pieces of its recording, so
    the line breaks where it left the recording and came back (outside ``output.record_radius_m``
    of every ego for a while: steps missing), instead of a straight line across the map."""
    x, y = g["x"].to_numpy(float), g["y"].to_numpy(float)
    if "step" in g:
        gaps = np.diff(g["step"].to_numpy(float)) > 1.5
    else:
        dt = np.diff(g["time_s"].to_numpy(float))
        gaps = dt > 1.5 * np.min(dt[dt > 0], initial=np.inf)
    cut = np.flatnonzero(gaps) + 1
    return (np.insert(x, cut, np.nan), np.insert(y, cut, np.nan)) if len(cut) else (x, y)


def _zoom_centre(groups, ego_ids, coll):
    """Where a close-up helps: the first collision, else the middle of an ego's largest turn (the
    point where its heading is halfway between start and end, if they differ by > 45 degrees, e.g.
    a turn at a junction); None for a run that just goes along a road."""
    if coll:
        return float(coll[0][0]), float(coll[0][1])
    for vid in ego_ids:
        g = groups[vid]
        h = np.unwrap(g["heading"].to_numpy(float))
        if len(h) < 3 or abs(h[-1] - h[0]) < np.radians(45):
            continue
        k = int(np.argmax((h - h[0]) * np.sign(h[-1] - h[0]) >= 0.5 * abs(h[-1] - h[0])))
        return float(g["x"].iloc[k]), float(g["y"].iloc[k])
    return None


_CORNERS = {"lower left": (0.09, 0.08), "lower right": (0.56, 0.08), "upper left": (0.09, 0.52),
            "upper right": (0.56, 0.52)}  # lower-left corners (axes fraction) of a 0.42 x 0.42 close-up,
# inset from the axes' edges so that its own tick labels do not cover the main ones


def _emptiest_corners(traj, xmin, xmax, ymin, ymax) -> list[str]:
    """The axes' four corners (boxes of 42 % x 42 %) ordered from the fewest trajectory points in them."""
    fx = (traj["x"].to_numpy(float) - xmin) / (xmax - xmin)
    fy = (traj["y"].to_numpy(float) - ymin) / (ymax - ymin)
    count = {c: int(np.sum((fx >= x0) & (fx <= x0 + 0.42) & (fy >= y0) & (fy <= y0 + 0.42)))
             for c, (x0, y0) in _CORNERS.items()}
    return sorted(count, key=lambda c: (count[c], list(_CORNERS).index(c)))


def _on_boundary(road, line) -> bool:
    """True if a marking polyline lies on the area boundary (e.g. left edge of a one-way road)."""
    mid = 0.5 * (line[:-1] + line[1:])
    return bool(np.all(road.area.boundary.distance(_points(mid)) < 0.05))


def _points(xy):
    return shapely.points(np.asarray(xy, float))


def plot_timeseries(series: "pd.DataFrame", out_png, title: str = "") -> str:
    """One stacked subplot per numeric metric column, sharing the ``time_s`` axis.

    If an ``id`` column is present, one line per id is drawn in every subplot.
    """
    skip = {"time_s", "id", "step"}
    metrics = [c for c in series.columns if c not in skip and np.issubdtype(series[c].dtype, np.number)]
    n = max(len(metrics), 1)
    fig = _new_figure((10.0, 1.0 + 2.0 * n))
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    t_key = "time_s" if "time_s" in series else series.columns[0]
    groups = list(series.groupby(series["id"].astype(str))) if "id" in series else [("", series)]
    for ax, col in zip(axes, metrics):
        for name, g in groups:
            g = g.sort_values(t_key)
            ax.plot(g[t_key], g[col], lw=1.4, label=name or None)
        vals = series[col].to_numpy(float)
        crosses_zero = np.isfinite(vals).any() and np.nanmin(vals) < 0 < np.nanmax(vals)
        if crosses_zero or col.endswith(("gap_m", "dist_m", "distance_m")):
            ax.axhline(0.0, color="#e00000", lw=0.8, ls="--")
        ax.set_ylabel(col, fontsize=9)
        ax.grid(True, alpha=0.4)
        if len(groups) > 1 and len(groups) <= 10:
            ax.legend(fontsize=7, loc="best")
    if not metrics:
        axes[0].text(0.5, 0.5, "no metric columns", ha="center", va="center", transform=axes[0].transAxes)
    axes[-1].set_xlabel("time [s]")
    if title:
        axes[0].set_title(title)
    fig.align_ylabels(axes)
    return _save(fig, out_png)

