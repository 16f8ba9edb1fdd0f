"""The junction box (safety/junction_box.py): the ego does not enter a junction it could not leave.

Hand-computed: the strip an ego 1.8 m wide sweeps along a straight path, and which standing vehicles
touch it. Real SUMO: a netconvert crossroads (tests/data/junction_box) where a car stands on the exit edge just beyond the
junction for 25 s; the ego waits before the stop line, not inside the junction behind it."""
import pathlib
import shutil
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import netconvert

from sumo_avoid.road.network import Road
from sumo_avoid.road.polyline import polyline_point_at
from sumo_avoid.runs import outputs, runner
from sumo_avoid.safety import junction_box, traffic as rules
from sumo_avoid.scenario import spec as scenario

DATA = pathlib.Path(__file__).parent.parent / "data" / "junction_box"
PATH = np.array([[0.0, 0.0], [100.0, 0.0]])


def _snap(rows):
    """A snapshot of vehicles [(x, y, heading, speed, is_person)] 5 m x 1.8 m; row 0 is the ego at (0, 0)."""
    rows = [(0.0, 0.0, 0.0, 0.0, False)] + rows
    a = np.array([r[:4] for r in rows], float)
    return SimpleNamespace(n=len(rows), pos=a[:, :2], heading=a[:, 2], speed=a[:, 3],
                           is_person=np.array([r[4] for r in rows]), length=np.full(len(rows), 5.0),
                           width=np.full(len(rows), 1.8))


def test_strip_tiles_the_path():
    boxes = junction_box.strip(PATH, 40.0, 60.0, 2.2)
    assert boxes.shape == (20, 4, 2)
    assert np.isclose(boxes[..., 0].min(), 40.0 - 0.025) and np.isclose(boxes[..., 0].max(), 60.0 + 0.025)
    assert np.allclose(np.abs(boxes[..., 1]), 1.1)


@pytest.mark.parametrize("vehicle, inside", [
    ((50.0, 2.0, 0.0, 0.0, False), True),  # its side at y 1.1: touches the strip (0.9 + 0.2 margin)
    ((50.0, 2.05, 0.0, 0.0, False), False),  # 0.05 m off it
    ((50.0, 3.5, np.pi / 2, 0.0, False), True),  # across the path, its front 1.0 m from the centre line
    ((50.0, 0.0, 0.0, 2.0, False), False),  # moving: it clears the junction
    ((50.0, 0.0, 0.0, 0.0, True), False),  # a person: the crossing rule's business
    ((63.0, 0.0, 0.0, 0.0, False), False),  # rear at 60.5: beyond the box (the exit's room is room_beyond's)
    ((62.5, 0.0, 0.0, 0.0, False), True),  # rear at 60.0: in it
])
def test_who_stands_in_the_box(vehicle, inside):
    assert junction_box.stands_in_box(PATH, 40.0, 60.0, _snap([vehicle]), 0, 1.8) is inside


@pytest.mark.parametrize("vehicles, shift, inside", [
    ([(50.0, 2.0, 0.0, 0.0, False)], 0.7, False),  # its side at y 1.1: the strip moved 0.7 m right ends at y 0.4
    ([(50.0, 1.5, 0.0, 0.0, False)], 0.7, False),  # its side at y 0.6: still clear of [-1.8, 0.4]
    ([(50.0, 1.2, 0.0, 0.0, False)], 0.7, True),  # its side at y 0.3: in the moved strip too
    ([(50.0, 0.5, 0.0, 0.0, False)], 0.7, True),  # across the middle: in every strip
    ([(50.0, 2.0, 0.0, 0.0, False), (50.0, -2.0, 0.0, 0.0, False)], 0.7, True),  # one on each side: no way past
    ([(50.0, 2.0, 0.0, 0.0, False)], 0.0, True),  # no room in the lane to move over
])
def test_room_to_pass_within_the_lane(vehicles, shift, inside):
    assert junction_box.stands_in_box(PATH, 40.0, 60.0, _snap(vehicles), 0, 1.8, shift) is inside


def test_lane_slack_is_half_the_narrowest_lanes_spare_width():
    piece = lambda a, b, w: SimpleNamespace(s_start_m=a, s_end_m=b, lane=1, widths_m=(1.0, w))
    task = SimpleNamespace(lanes=(piece(0.0, 40.0, 2.0), piece(40.0, 50.0, 3.2), piece(50.0, 60.0, 3.0), piece(60.0, 90.0, 2.0)))
    assert junction_box.lane_slack(task, 40.0, 60.0, 1.8) == pytest.approx(0.6)  # (3.0 - 1.8) / 2; the 2.0 m lanes are outside
    assert junction_box.lane_slack(task, 0.0, 60.0, 1.8) == pytest.approx(0.1)
    assert junction_box.lane_slack(task, 0.0, 40.0, 2.2) == 0.0  # a lane narrower than the ego: none
    assert junction_box.lane_slack(SimpleNamespace(lanes=()), 0.0, 40.0, 1.8) == 0.0


@pytest.fixture(scope="module")
def crossroads(tmp_path_factory):
    d = tmp_path_factory.mktemp("box")
    netconvert("junction_box", d, "x")
    for f in ("x.rou.xml", "x.toml"):
        shutil.copy(DATA / f, d / f)
    return d


def test_junction_exits_on_a_netconvert_crossroads(crossroads):
    plan = Road.from_net_file(str(crossroads / "x.net.xml")).route(["AB", "BC"])
    (link,), (s_exit,) = plan.links, junction_box.junction_exits(
        SimpleNamespace(links=plan.links, lanes=plan.lanes))
    bc = [p for p in plan.lanes if p.edge == "BC"][0]
    assert s_exit == bc.s_start_m and s_exit > link.s_stop_m


def _front_x_while_blocked(crossroads, monkeypatch, box: bool):
    if not box:
        monkeypatch.setattr(rules, "box_cap", lambda *a, **k: (float("inf"), -1.0))
    res = runner.run(scenario.load(crossroads / "x.toml"))
    ego = res.traj[res.traj["id"] == "ego"].sort_values("step")
    blocked = ego[ego["time_s"] < 24.0]
    front = blocked["x"] + 2.5 * np.cos(blocked["heading"])
    return float(front.max()), outputs.run_metrics(res)


@pytest.mark.sumo
def test_the_ego_waits_before_a_junction_it_could_not_leave(crossroads, monkeypatch):
    plan = Road.from_net_file(str(crossroads / "x.net.xml")).route(["AB", "BC"])
    line_x = float(polyline_point_at(plan.path, plan.links[0].s_stop_m)[0])
    front, m = _front_x_while_blocked(crossroads, monkeypatch, box=True)
    assert front <= line_x + 0.1  # waited before the stop line while the car stood beyond the junction
    assert m["goal_reached"] and m["collisions"] == 0 and m["rules_yields"] >= 1
    front, _ = _front_x_while_blocked(crossroads, monkeypatch, box=False)
    assert front > line_x + 3.0  # without the rule it drives into the junction and stands there
