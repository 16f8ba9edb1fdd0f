"""Figures render to non-trivial PNGs from a tiny synthetic run on the real overtaking road."""
from __future__ import annotations

import pathlib

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.plots.trajectories import (
    footprint_corners,
    plot_timeseries,
    plot_trajectories,
)
from sumo_avoid.road.network import Road

NETS = pathlib.Path(__file__).resolve().parents[2] / "nets"
COLUMNS = ["step", "time_s", "id", "is_ego", "x", "y", "vx", "vy", "speed", "heading", "length", "width"]


def synthetic_traj(duration_s: float = 20.0, dt: float = 0.5) -> pd.DataFrame:
    """Ego overtakes a slow leader on the overtaking road: lane 0 -> lane 1 -> lane 0."""
    t = np.arange(0.0, duration_s + 1e-9, dt)
    rows = []
    lane_y = [-12.25, -8.75, -5.25, -1.75]
    ego_x = 20.0 + 25.0 * t
    ego_y = lane_y[0] + (lane_y[1] - lane_y[0]) * np.clip(np.minimum((t - 2) / 3, (16 - t) / 3), 0, 1)
    vy = np.gradient(ego_y, dt)
    for k, ti in enumerate(t):
        rows.append([k, ti, "ego", True, ego_x[k], ego_y[k], 25.0, vy[k], np.hypot(25.0, vy[k]),
                     np.arctan2(vy[k], 25.0), 4.5, 1.8])
        rows.append([k, ti, "slow", False, 80.0 + 12.0 * ti, lane_y[0], 12.0, 0.0, 12.0, 0.0, 4.5, 1.8])
        rows.append([k, ti, "truck", False, 10.0 + 20.0 * ti, lane_y[2], 20.0, 0.0, 20.0, 0.0, 12.0, 2.5])
    return pd.DataFrame(rows, columns=COLUMNS)


def test_footprint_corners():
    c = footprint_corners([0.0], [0.0], [np.pi / 2], [4.0], [2.0])
    assert c.shape == (1, 4, 2)
    assert c[0, 0] == pytest.approx([1.0, 2.0])  # front-right of a car heading north (geometry order)
    assert c[0, 1] == pytest.approx([-1.0, 2.0])  # then front-left, CCW


def test_plot_trajectories_writes_png(tmp_path):
    road = Road.from_net_file(NETS / "overtaking.net.xml")
    traj = synthetic_traj()
    coll = pd.DataFrame({"time_s": [12.0], "id": ["ego"], "other_id": ["slow"], "x": [320.0], "y": [-10.5]})
    obstacle = np.array([[400.0, -4.0], [404.0, -4.0], [404.0, -6.5], [400.0, -6.5]])
    out = plot_trajectories(road, traj, tmp_path / "traj.png", collisions=coll, goals={"ego": (530.0, -12.25)},
                            title="synthetic overtaking", obstacles=[obstacle])
    p = pathlib.Path(out)
    assert p.exists() and p.stat().st_size > 20_000


def test_plot_trajectories_junction_and_position_lookup(tmp_path):
    road = Road.from_net_file(NETS / "left_turn.net.xml")
    path = road.route_path(["S2C", "C2W"])
    s = np.linspace(180.0, 300.0, 61)
    xy = np.array([road.polyline_point_at(path, si) for si in s])
    hd = np.arctan2(*np.gradient(xy, axis=0)[:, ::-1].T)
    traj = pd.DataFrame({"step": np.arange(61), "time_s": np.arange(61) * 0.2, "id": "ego", "is_ego": True,
                         "x": xy[:, 0], "y": xy[:, 1], "vx": 0.0, "vy": 0.0, "speed": 10.0, "heading": hd,
                         "length": 4.5, "width": 1.8})
    coll = pd.DataFrame({"step": [30], "id": ["ego"], "other_id": ["ped"]})  # no x/y: looked up
    out = tmp_path / "sub" / "turn.png"
    plot_trajectories(road, traj, out, collisions=coll, goals={"ego": xy[-1]})
    assert out.exists() and out.stat().st_size > 10_000


def test_plot_timeseries_writes_png(tmp_path):
    t = np.arange(0.0, 20.0, 0.5)
    series = pd.DataFrame({"time_s": t, "min_gap_m": 30 - 1.5 * t, "ego_speed_mps": 25 + np.sin(t)})
    out = plot_timeseries(series, tmp_path / "ts.png", "synthetic metrics")
    p = pathlib.Path(out)
    assert p.exists() and p.stat().st_size > 10_000


def test_turn_gets_a_close_up_and_a_straight_run_does_not():
    """The middle of an ego's largest turn (heading change > 45 degrees) or its first collision is
    where the close-up goes; a run along a road gets none. The close-up sits in the emptiest corner."""
    from sumo_avoid.plots.trajectories import _emptiest_corners, _zoom_centre

    t = np.linspace(0.0, np.pi / 2, 91)  # quarter circle of radius 20 m about (0, 0), heading north -> west
    x, y = 20.0 * np.cos(t), 20.0 * np.sin(t)
    g = pd.DataFrame({"x": x, "y": y, "heading": t + np.pi / 2})
    cx, cy = _zoom_centre({"ego": g}, ["ego"], [])
    assert (cx, cy) == pytest.approx((20.0 * np.cos(np.pi / 4), 20.0 * np.sin(np.pi / 4)), abs=0.3)
    straight = pd.DataFrame({"x": np.linspace(0, 500, 50), "y": 0.0, "heading": 0.1 * np.sin(np.arange(50))})
    assert _zoom_centre({"ego": straight}, ["ego"], []) is None
    assert _zoom_centre({"ego": straight}, ["ego"], [(100.0, 2.0, "ego × car")]) == (100.0, 2.0)
    pts = pd.DataFrame({"x": [90.0, 95.0, 10.0], "y": [90.0, 95.0, 90.0]})  # two in the upper right, one upper left
    order = _emptiest_corners(pts, 0.0, 100.0, 0.0, 100.0)
    assert order[:2] == ["lower left", "lower right"] and order[-1] == "upper right"


@pytest.mark.sumo
def test_a_vehicle_that_leaves_and_reenters_the_recording_is_drawn_in_pieces(tmp_path):
    """Real SUMO on the overtaking road: two egos stand 700 m apart, 'v' drives past both at 25 m/s;
    with a 40 m recording radius it is recorded near a, then not, then near b. Its drawn line breaks
    there: no segment of it jumps across the unrecorded 600 m (it did: a straight line across)."""
    from sumo_avoid.plots.trajectories import _draw, _new_figure, track_xy
    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec as scenario

    (tmp_path / "r.rou.xml").write_text("""<routes>
  <vType id="car" length="4.5" width="1.8" sigma="0" maxSpeed="30"/>
  <route id="road" edges="road"/>
  <vehicle id="a" type="car" route="road" depart="0" departLane="0" departPos="200" departSpeed="0"/>
  <vehicle id="b" type="car" route="road" depart="0" departLane="0" departPos="900" departSpeed="0"/>
  <vehicle id="v" type="car" route="road" depart="0" departLane="2" departPos="10" departSpeed="25"/>
</routes>""")
    path = tmp_path / "s.toml"
    path.write_text(f'name = "pieces"\n[sim]\nnet = "{NETS / "overtaking.net.xml"}"\nroutes = ["r.rou.xml"]\n'
                    'duration_s = 40.0\n[ego]\nids = ["a", "b"]\ncontroller = "scripted"\n'
                    '[controllers.scripted]\nspeed_mps = 0.0\n[output]\nrecord_radius_m = 40.0\n')
    res = runner.run(scenario.load(path))
    v = res.traj[res.traj["id"] == "v"].sort_values("step")
    assert np.diff(v["step"].to_numpy()).max() > 100  # the gap: more than 10 s unrecorded
    x, _ = track_xy(v)
    assert np.isnan(x).sum() == 1 and len(x) == len(v) + 1
    fig = _new_figure((8, 3))
    ax = fig.add_subplot(1, 1, 1)
    traj = res.traj.sort_values(["id", "step"])
    groups = {k: g for k, g in traj.groupby("id")}
    _draw(ax, Road.from_net_file(NETS / "overtaking.net.xml"), groups, ["a", "b"], ["v"], [], {}, [])
    line, = [ln for ln in ax.lines if ln.get_gid() == "track:v"]
    xs = np.asarray(line.get_xdata(), float)
    steps = np.diff(xs)
    assert np.nanmax(np.abs(steps)) < 5.0  # 25 m/s x 0.1 s per step, never across the gap
    assert xs[np.isfinite(xs)].max() - xs[np.isfinite(xs)].min() > 600  # both pieces are drawn
    plot_trajectories(Road.from_net_file(NETS / "overtaking.net.xml"), res.traj, tmp_path / "t.png")
    assert (tmp_path / "t.png").stat().st_size > 10_000
