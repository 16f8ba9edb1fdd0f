"""Oncoming lanes a net lays over the ego's own narrow its corridor (real nets netconvert builds here; unseen
Cologne, Am Heumarkt: two one-way edges whose lane centres are 1.8-2.3 m apart at 3.2 m width). Hand values:
the ego's lane centre at y = -1.6 (its left border y = 0), the oncoming lane's centre ``gap`` m to its left, so
the oncoming lane reaches 3.2 - gap m over the ego's left border."""
from __future__ import annotations

import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.road import network
from sumo_avoid.road.overlaps import MIN_HALF_ROOM_M
from sumo_avoid.road.route_lanes import RouteLanes

pytestmark = pytest.mark.sumo
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"


def _net(tmp_path, gap: float, z: float = 0.0, allow: str = "", same_nodes: bool = False) -> pathlib.Path:
    y = -1.6 + gap - 1.6  # the westbound edge's line: its lane lies 1.6 m to its right (north)
    far = "" if same_nodes else '<node id="P" x="210" y="{y}" z="{z}"/><node id="Q" x="-210" y="{y}" z="{z}"/>'
    (tmp_path / "o.nod.xml").write_text(
        '<nodes><node id="W" x="-200" y="0"/><node id="E" x="200" y="0"/>' + far.format(y=y, z=z) + "</nodes>")
    ends = 'from="E" to="W"' if same_nodes else 'from="P" to="Q"'
    shape = f' shape="200,{y} -200,{y}"' if same_nodes else ""
    allowed = f' allow="{allow}"' if allow else ""
    (tmp_path / "o.edg.xml").write_text(
        '<edges><edge id="east" from="W" to="E" numLanes="1" speed="13.89" width="3.2"/>'
        f'<edge id="west" {ends} numLanes="1" speed="13.89" width="3.2"{shape}{allowed}/></edges>')
    net = tmp_path / "o.net.xml"
    subprocess.run([str(BIN / "netconvert"), "-n", str(tmp_path / "o.nod.xml"), "-e", str(tmp_path / "o.edg.xml"),
                    "--offset.disable-normalization", "true", "--no-turnarounds", "true", "-o", str(net)],
                   check=True, capture_output=True)
    return net


def _left_cut(net) -> tuple[np.ndarray, np.ndarray, RouteLanes]:
    plan = network.Road.from_net_file(net).route(["east"], vclass="passenger")
    (piece,) = plan.lanes
    lanes = RouteLanes(plan.lanes)
    s = np.linspace(piece.s_start_m + 20.0, piece.s_end_m - 20.0, 50)
    return s, lanes.corridor(s)[1], lanes


@pytest.mark.parametrize("gap, cut", [(2.9, 0.3), (2.0, 1.6 - MIN_HALF_ROOM_M)], ids=["overlap_0.3", "capped"])
def test_an_oncoming_lane_over_the_ego_s_moves_its_left_border_back(tmp_path, gap, cut):
    s, hi, lanes = _left_cut(_net(tmp_path, gap))
    np.testing.assert_allclose(hi, 1.6 - cut, atol=0.02)  # the path runs on the lane centre
    lo = lanes.corridor(s)[0]
    np.testing.assert_allclose(lo, -1.6, atol=1e-9)  # the right border stays


@pytest.mark.parametrize("case", ["bridge", "tram_track", "own_opposite_edge", "apart"])
def test_no_narrowing_where_the_lane_is_no_oncoming_traffic_of_the_ego_s_kind(tmp_path, case):
    kw = {"bridge": dict(gap=2.6, z=8.0), "tram_track": dict(gap=2.6, allow="tram"),
          "own_opposite_edge": dict(gap=2.6, same_nodes=True), "apart": dict(gap=3.2)}[case]
    net = _net(tmp_path, **kw)
    west = np.asarray(network.Road.from_net_file(net)._net.getLane("west_0").getShape())
    np.testing.assert_allclose(west[:, 1], -1.6 + kw["gap"], atol=0.05)  # the lane is where the case puts it
    _, hi, lanes = _left_cut(net)
    assert all(not p.narrowing_m for p in lanes.pieces)
    np.testing.assert_allclose(hi, 1.6, atol=1e-9)
