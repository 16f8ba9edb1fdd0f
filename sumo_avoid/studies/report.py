"""``sumo-avoid report LEDGER_OR_RUN_DIR --out FILE.html``: a self-contained study report.

The HTML file needs nothing else: images are PNGs embedded as base64 ``data:`` URIs, styles are
inline, there are no scripts and no links to fetch. Sections: a table per scenario x controller x
every dimension the batch varied (:func:`varied`: --set and grid keys whose value differs between
runs), a trajectory plot on the road geometry per such group, box plots of each metric across
seeds, time series of gap and speed for one chosen run, every run, and the failed runs with their errors.
``--md`` / ``--csv`` export the summary table as Markdown and the runs table as CSV. Each done run's
viewer (:mod:`sumo_avoid.watch.viewer`) is written to ``REPORT_viewers/KEY.html`` and linked from the
runs table (``--no-viewers``: not); ``report RUN_DIR`` of one run folder writes that run's viewer
(``--out``, default ``RUN_DIR/viewer.html``).

The input is a ledger (``.sqlite``), a folder holding ``ledger.sqlite``, or a folder of run
folders written by ``sumo-avoid run`` (each with ``metrics.json``), or one such run folder.
"""
from __future__ import annotations

import base64
import contextlib
import datetime
import html
import io
import json
import pathlib
import tempfile
import types

import pandas as pd

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.metrics.series import series
from sumo_avoid.plots.trajectories import (
    _new_figure,
    plot_timeseries,
    plot_trajectories,
)
from sumo_avoid.studies import baseline, ledger, viewer_links
from sumo_avoid.studies.files import CL, check_out_file, make_dirs, remove_dirs, write_atomic
from sumo_avoid.studies.watch_cmd import write_viewer
from sumo_avoid.road.network import Road

METRICS = ("collisions", "vru_collisions", "collisions_ego_stopped", "max_impact_speed_mps", "min_gap_m", "phi_coll",
           "phi_wall", "mean_speed_mps", "time_to_goal_s",
           "path_length_m", "sumo_collisions", "min_ttc_s", "min_ttc2d_s", "max_drac_mps2", "min_pet_s",
           "wrong_way_m", "off_road_m", "max_abs_jerk_mps3", "max_lat_accel_mps2")

NEEDS = ("key", "scenario", "controller", "seed", "status", "error")  # the ledger columns a report reads
DERIVED = (baseline.COLUMN,)  # columns computed across the runs (studies/baseline.py), shown beside METRICS


def load_runs(src) -> tuple:
    """(runs DataFrame with ``travel_time_ratio``, base folder for the ``artifacts`` column). Raises
    ScenarioError naming the file for input that is no ledger and no run folder."""
    src = pathlib.Path(src)
    if src.is_dir() and (src / "ledger.sqlite").is_file():
        src = src / "ledger.sqlite"
    if src.is_file():
        ledger.check(src, "LEDGER_OR_RUN_DIR", new_ok=False, needs=NEEDS)
        return baseline.with_travel_time_ratio(ledger.read(src)), src.resolve().parent
    if not src.is_dir():
        raise ScenarioError(str(src), "<file>", "a ledger file or a folder of runs (no such file)", show_got=False)
    dirs = [src] if (src / "metrics.json").is_file() else sorted(p.parent for p in src.glob("*/metrics.json"))
    if not dirs:
        raise ScenarioError(str(src), "<file>", "a ledger.sqlite or run folders with metrics.json in this folder",
                            show_got=False)
    rows = []
    for d in dirs:
        m = _metrics(d / "metrics.json")
        row = {"key": d.name, "status": "done", "error": None, "artifacts": str(d.resolve()), "net_file": None}
        row.update(ledger.scalar_metrics(m))
        row.update(scenario=m.get("scenario"), controller=m.get("controller"), seed=m.get("seed"))
        rows.append(row)
    return baseline.with_travel_time_ratio(pd.DataFrame(rows)), src.resolve()


def _metrics(path: pathlib.Path) -> dict:
    """A run's metrics.json as written by ``sumo-avoid run`` (a JSON object)."""
    try:
        m = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as e:
        raise ScenarioError(str(path), "<file>", f"a metrics.json written by a run ({e})", show_got=False) from None
    if not isinstance(m, dict):
        raise ScenarioError(str(path), "<file>", "a metrics.json written by a run (a JSON object)",
                            type(m).__name__, show_got=True)
    return m


GROUP = ["scenario", "controller"]
SCENARIO_VALUE = "(scenario)"  # a key a run did not override: the scenario file's value
_NOT_DIMENSIONS = {"ego.controller", "sim.seed"}  # shown as the controller and seed columns


def _overrides(text) -> dict:
    """A ledger row's ``overrides`` (JSON list of KEY=VALUE: --set and grid points) as key -> value text."""
    try:
        items = json.loads(text) if isinstance(text, str) else []
    except ValueError:
        items = []
    out = {}
    for item in items if isinstance(items, list) else []:
        key, _, value = str(item).partition("=")
        out[key.strip()] = value.strip().strip('"')
    return out


def varied(df) -> tuple:
    """(runs, group columns): scenario, controller, then every --set / grid key whose value differs
    between the runs (e.g. ego.sensor, controllers.apf_sa.k_rep), each added as a column of its value
    in that run, or "(scenario)" where the run kept the scenario file's."""
    if "overrides" not in df or df.empty:
        return df, list(GROUP)
    parsed = [_overrides(v) for v in df["overrides"]]
    keys = sorted({k for p in parsed for k in p} - _NOT_DIMENSIONS)
    dims = [k for k in keys if len({p.get(k, SCENARIO_VALUE) for p in parsed}) > 1]
    return df.assign(**{k: [p.get(k, SCENARIO_VALUE) for p in parsed] for k in dims}), [*GROUP, *dims]


def _label(key, group) -> str:
    return " · ".join(f"{c.rsplit('.', 1)[-1]}={v}" if "." in c else str(v) for c, v in zip(group, key))


def summary(df):
    """Table of runs, failures and aggregate metrics over done runs, a row per scenario x controller
    x every value of what the batch varied (:func:`varied`)."""
    df, group = varied(df)
    rows = []
    for key, g in df.groupby(group, sort=True, dropna=False):
        d = g[g["status"] == "done"]

        def agg(col, fn):
            if col not in d or d[col].dropna().empty:
                return None
            return float(getattr(d[col].dropna().astype(float), fn)())

        rows.append({**dict(zip(group, key)), "runs": len(g), "done": len(d), "failed": len(g) - len(d),
                     "goal_reached_rate": agg("goal_reached", "mean"), "collisions_total": agg("collisions", "sum"),
                     "vru_collisions_total": agg("vru_collisions", "sum"),
                     "collisions_ego_stopped_total": agg("collisions_ego_stopped", "sum"),
                     "min_gap_m_min": agg("min_gap_m", "min"), "phi_wall_max": agg("phi_wall", "max"),
                     "phi_coll_mean": agg("phi_coll", "mean"), "mean_speed_mps_mean": agg("mean_speed_mps", "mean"),
                     "min_ttc_s_min": agg("min_ttc_s", "min"), "min_ttc2d_s_min": agg("min_ttc2d_s", "min"),
                     "wrong_way_m_max": agg("wrong_way_m", "max"), "off_road_m_max": agg("off_road_m", "max"),
                     "travel_time_ratio_median": agg(baseline.COLUMN, "median")})
    return pd.DataFrame(rows)


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _png_file(path: pathlib.Path) -> str:
    return base64.b64encode(path.read_bytes()).decode("ascii")


def _img(b64: str, alt: str) -> str:
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{b64}">'


def box_plots(df) -> str | None:
    """One panel per metric: a box per scenario/controller over its done runs' seeds."""
    df, group = varied(df)
    d = df[df["status"] == "done"]
    cols = [c for c in (*METRICS, *DERIVED) if c in d and d[c].notna().any()]
    if not cols or d.empty:
        return None
    groups = list(d.groupby(group, sort=True))
    n = len(cols)
    ncol = min(3, n)
    nrow = -(-n // ncol)
    fig = _new_figure((5.0 * ncol, 3.2 * nrow))
    for i, c in enumerate(cols):
        ax = fig.add_subplot(nrow, ncol, i + 1)
        data = [g[c].dropna().astype(float).to_numpy() for _, g in groups]
        labels = [_label(k, group).replace(" · ", "\n") for k, _ in groups]
        try:
            ax.boxplot(data, tick_labels=labels, showmeans=True)
        except TypeError:  # matplotlib < 3.9
            ax.boxplot(data, labels=labels, showmeans=True)
        ax.set_title(c, fontsize=10)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return _png(fig)


def _artifacts(row, base: pathlib.Path) -> pathlib.Path | None:
    a = row.get("artifacts")
    if not isinstance(a, str) or not a:
        return None
    p = pathlib.Path(a)
    return p if p.is_absolute() else base / p


def trajectory_png(row, base: pathlib.Path) -> str | None:
    """The run's trajectory on the road: its trajectory.png, or drawn from trajectories.csv + net."""
    d = _artifacts(row, base)
    if d is None:
        return None
    if (d / "trajectory.png").is_file():
        return _png_file(d / "trajectory.png")
    net = row.get("net_file")
    if not (d / "trajectories.csv").is_file() or not isinstance(net, str) or not pathlib.Path(net).is_file():
        return None
    return _drawn(d / "trajectory.png", lambda out: plot_trajectories(
        Road.from_net_file(net), pd.read_csv(d / "trajectories.csv"), out,
        title=f"{row['scenario']} · {row['controller']} · seed {row['seed']}"))


def timeseries_png(row, base: pathlib.Path) -> str | None:
    """Gap and speed over time for one run: its timeseries.png, or computed from trajectories.csv."""
    d = _artifacts(row, base)
    if d is None:
        return None
    if (d / "timeseries.png").is_file():
        return _png_file(d / "timeseries.png")
    if not (d / "trajectories.csv").is_file():
        return None
    return _drawn(d / "timeseries.png", lambda out: plot_timeseries(
        series(types.SimpleNamespace(traj=pd.read_csv(d / "trajectories.csv"))), out,
        title=f"{row['scenario']} · {row['controller']} · seed {row['seed']}"))


def _drawn(cache: pathlib.Path, draw) -> str:
    """A plot drawn into the run's folder (kept for the next report), or, where that folder cannot be
    written (read-only, full), into a temporary folder: the report needs no write beside the ledger."""
    try:
        draw(cache)
        return _png_file(cache)
    except OSError:  # a half-drawn file would be taken for the plot next time
        with contextlib.suppress(OSError):
            cache.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-report-") as tmp:
        draw(pathlib.Path(tmp) / cache.name)
        return _png_file(pathlib.Path(tmp) / cache.name)


def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and v != v):
        return "n/a"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def _table_html(df, cols, raw=()) -> str:
    """``raw``: columns holding HTML already (the viewer links)."""
    head = "".join(f"<th>{html.escape(c)}</th>" for c in cols)
    body = "".join("<tr>" + "".join(f"<td>{r[c] if c in raw else html.escape(_fmt(r[c]))}</td>" for c in cols) + "</tr>"
                   for r in df.to_dict(orient="records"))
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def markdown(df, cols) -> str:
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(_fmt(r[c]).replace("|", "\\|") for c in cols) + " |" for r in df.to_dict(orient="records")]
    return "\n".join(lines) + "\n"


CSS = ("body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse;margin:1em 0;"
       "font-size:13px}td,th{border:1px solid #bbb;padding:3px 7px;text-align:right}th{background:#eee}"
       "img{max-width:100%;border:1px solid #ddd;margin:.5em 0}.failed td{background:#fde}")


def build_html(df, base: pathlib.Path, title: str, run_key: str | None = None, viewers: dict | None = None) -> str:
    """``viewers``: run key -> link of its viewer page (a column of the runs table)."""
    df, group = varied(df)
    summ = summary(df)
    done = df[df["status"] == "done"].sort_values(["scenario", "controller", "seed", "key"])
    failed = df[df["status"] != "done"]
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{CSS}</style></head><body><h1>{html.escape(title)}</h1>",
             f"<p>{len(df)} runs: {len(done)} done, {len(failed)} failed. Generated "
             f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC by sumo-avoid report.</p>",
             f"<h2>{' &times; '.join(html.escape(c) for c in group)}</h2>", f'<div id="summary">{_table_html(summ, list(summ.columns))}</div>']
    parts.append(f"<h2>Trajectories on the road (one run per {' × '.join(group)}, lowest seed)</h2>")
    for key, g in done.groupby(group, sort=True):
        row = g.iloc[0].to_dict()
        b64 = trajectory_png(row, base)
        head = html.escape(f"{_label(key, group)} · seed {row['seed']}")
        parts.append(f"<h3>{head}</h3>"
                     + (_img(b64, f"trajectory {_label(key, group)}") if b64 else "<p>(no trajectory recorded)</p>"))
    bp = box_plots(df)
    parts.append("<h2>Metric distributions across seeds</h2>" + (_img(bp, "box plots") if bp else "<p>no done runs</p>"))
    if len(done):
        chosen = done[done["key"].astype(str).str.startswith(run_key)] if run_key else done
        if chosen.empty:
            raise ValueError(f"--run {run_key}: no done run with a key starting so")
        row = chosen.iloc[0].to_dict()
        b64 = timeseries_png(row, base)
        parts.append(f"<h2>Gap and speed over time: {html.escape(str(row['scenario']))} · "
                     f"{html.escape(str(row['controller']))} · seed {row['seed']} ({html.escape(str(row['key'])[:16])})</h2>"
                     + (_img(b64, "time series") if b64 else "<p>(no trajectory recorded)</p>"))
    cols = ["key", *group, "seed", "status"] + [c for c in ("goal_reached", *METRICS, *DERIVED) if c in df]
    shown = df.sort_values(["scenario", "controller", "seed", "key"])
    if viewers is not None:
        cols.insert(1, "viewer")
        shown = shown.assign(viewer=[viewer_links.link(viewers.get(k)) for k in shown["key"]])
    shown = shown.assign(key=lambda x: x["key"].astype(str).str[:16])
    parts.append(f'<h2>Runs</h2><div id="runs">{_table_html(shown, cols, raw=("viewer",))}</div>')
    parts.append("<h2>Failed runs</h2>" + (f'<div id="failed" class="failed">'
                                          f'{_table_html(failed, ["key", "scenario", "controller", "seed", "error"])}</div>'
                                          if len(failed) else "<p>none</p>"))
    parts.append("</body></html>\n")
    return "\n".join(parts)


def add_parser(sub) -> None:
    r = sub.add_parser("report", help="self-contained HTML report of a ledger or of run folders")
    r.add_argument("source", type=pathlib.Path, metavar="LEDGER_OR_RUN_DIR")
    r.add_argument("--out", type=pathlib.Path, default=None,
                   help="HTML file to write (one run folder: its viewer, default RUN_DIR/viewer.html)")
    r.add_argument("--no-viewers", action="store_true", help="no viewer page per run beside the report")
    r.add_argument("--run", default=None, metavar="KEY", help="run (key prefix) for the time series (default: first)")
    r.add_argument("--md", type=pathlib.Path, default=None, help="also write the summary table as Markdown")
    r.add_argument("--csv", type=pathlib.Path, default=None, help="also write the runs table as CSV")
    r.add_argument("--title", default=None)
    r.set_defaults(func=cmd_report)


def cmd_report(args) -> int:
    if (args.source / "metrics.json").is_file():  # one run folder: its viewer
        return _one_run(args)
    if args.out is None:
        raise ScenarioError(CL, "--out", "an HTML file to write (needed for a ledger or a folder of runs)",
                            show_got=False)
    for flag, path in (("--out", args.out), ("--md", args.md), ("--csv", args.csv)):
        if path is not None:
            check_out_file(path, flag)  # before the (slow) report is built
    df, base = load_runs(args.source)
    made = [d for flag, path in (("--out", args.out), ("--md", args.md), ("--csv", args.csv)) if path is not None
            for d in make_dirs(path.parent, flag)]  # now: a folder that vanishes later is not made again
    try:
        _write(args, df, base)
    except BaseException:
        remove_dirs(made)
        raise
    return 0


def _one_run(args) -> int:
    """``report RUN_DIR``: the run's viewer page (:mod:`sumo_avoid.watch.viewer`)."""
    for flag, path in (("--md", args.md), ("--csv", args.csv), ("--run", args.run)):
        if path is not None:
            raise ScenarioError(CL, flag, "no table for one run folder (its viewer has its metrics)", str(path))
    out = args.out or args.source / "viewer.html"
    check_out_file(out, "--out")
    made = make_dirs(out.parent, "--out")
    try:
        write_viewer(args.source, out)
    except BaseException:
        remove_dirs(made)
        raise
    print(f"viewer -> {out}")
    return 0


def _write(args, df, base: pathlib.Path) -> None:
    planned = {} if args.no_viewers else viewer_links.plan(df, base, args.out)
    try:
        page = build_html(df, base, args.title or f"sumo-avoid study: {args.source}", args.run,
                          None if args.no_viewers else viewer_links.links(planned, args.out))
    except ValueError as e:
        raise ScenarioError(CL, "--run", f"the key (or a key prefix) of a done run ({e})", args.run) from None
    write_atomic(args.out, page)
    try:  # after the page: a folder that vanished or a full disk is named on the page's file first
        viewer_links.write_planned(planned)
    except BaseException:
        with contextlib.suppress(OSError):
            args.out.unlink()
        raise
    print(f"report -> {args.out} ({len(df)} runs)")
    if args.md:
        s = summary(df)
        failed = df[df["status"] != "done"]
        text = f"## {' x '.join(varied(df)[1])}\n\n" + markdown(s, list(s.columns))
        if len(failed):
            text += "\n## Failed runs\n\n" + markdown(failed, ["key", "scenario", "controller", "seed", "error"])
        write_atomic(args.md, text)
    if args.csv:
        write_atomic(args.csv, df.to_csv(index=False))
