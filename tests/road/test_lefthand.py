"""Left-hand traffic (a net netconvert builds with ``lefthand="true"``: the UK, Japan, India, Malaysia ...): lane 0
is the kerb lane on the *left* and the lane indices grow to the right. The route frame's lane centres and corridor
must lie where SUMO's lanes are, as in right-hand traffic."""
from __future__ import annotations

import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.control.road_view import RoadView
from sumo_avoid.core.types import EgoTask
from sumo_avoid.road import network

pytestmark = pytest.mark.sumo
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"


def _grid(tmp_path, lefthand: bool) -> pathlib.Path:
    net = tmp_path / f"{'lh' if lefthand else 'rh'}.net.xml"
    subprocess.run([str(BIN / "netgenerate"), "--grid", "--grid.number", "3", "--grid.length", "150", "-L", "3",
                    "--no-turnarounds", "true", "-o", str(net)] + (["--lefthand"] if lefthand else []),
                   check=True, capture_output=True)
    return net


@pytest.mark.parametrize("lefthand", [False, True], ids=["right_hand", "left_hand"])
@pytest.mark.parametrize("depart_lane", [0, 2])
def test_lane_centres_and_corridor_lie_on_sumos_lanes(tmp_path, lefthand, depart_lane):
    road = network.Road.from_net_file(_grid(tmp_path, lefthand))
    plan = road.route(["A0A1", "A1A2"], depart_lane=depart_lane, vclass="passenger")
    task = EgoTask("ego", plan.path[-1], plan.path, 13.89, plan.links, plan.speed_limits, plan.lanes)
    view = RoadView(task)
    s = 60.0  # the middle of A0A1 (north, 150 m long)
    centres = view.lane_centres(s)
    xy = view.frame.to_xy(np.full(3, s), centres + view.line.offset([s])[0])
    for k in range(3):
        shape = np.asarray(road._net.getLane(f"A0A1_{k}").getShape())
        assert abs(xy[k][0] - shape[0][0]) < 0.05  # lane k's centre is at lane k's x (A0A1 runs along +y)
    lo, hi = view.corridor([s])
    edges_x = [np.asarray(road._net.getLane(f"A0A1_{k}").getShape())[0][0] for k in (0, 2)]
    span = view.frame.to_xy(np.full(2, s), np.array([lo[0], hi[0]]) + view.line.offset([s])[0])[:, 0]
    assert sorted(span) == pytest.approx(sorted([edges_x[0] - 1.6 * np.sign(edges_x[1] - edges_x[0]),
                                                 edges_x[1] + 1.6 * np.sign(edges_x[1] - edges_x[0])]), abs=0.05)
