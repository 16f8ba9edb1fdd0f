"""Wide exits (safety/wide_turns.py): a turn too tight for the car sweeps the oncoming lane of its
exit edge; the rules layer holds the ego at its line until that lane is clear.

Hand-computed: :func:`oncoming_first` on made-up lanes. Real SUMO: tests/data/tight_turn with the
exit edge at 130 deg (a right turn netconvert draws at a 2 m junction radius; the car turns at
4.25 m), an oncoming car timed to meet the ego at the exit."""
import math
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.runs import outputs
from sumo_avoid.core.types import EgoTask
from sumo_avoid.runs import runner
from sumo_avoid.safety import traffic as rules
from sumo_avoid.safety.wide_turns import (
    TURN_CRAWL_MPS,
    WideExit,
    oncoming_first,
    wide_exits,
)
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.road.network import Road

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
DATA = pathlib.Path(__file__).parent.parent / "data" / "tight_turn"
# lane L: one of its links gives way to the ego's (a car standing there may wait for the ego); K: none does
WIDE = WideExit(120.0, (("L", 80.0, True), ("K", 80.0, False)), inside=("I",), leaving=("B",))


def _first(rows, standing=None, ego_row=-1):
    """oncoming_first for the ego's front at s = 110 m and vehicles [(lane, lane_pos, speed)]."""
    lanes: dict[str, list[int]] = {}
    for r, (lane, _, _) in enumerate(rows):
        lanes.setdefault(lane, []).append(r)
    return oncoming_first(WIDE, 110.0, lanes, np.array([p for _, p, _ in rows], float),
                          np.array([v for _, _, v in rows], float), standing, ego_row)


def test_a_vehicle_queued_before_the_point_for_good_does_not_come():
    # now 100 s, wait 30 s: stood since 60 s (40 s) it stands for good, since 80 s (20 s) not yet
    good, not_yet = (100.0, 30.0, lambda r, tls: 60.0), (100.0, 30.0, lambda r, tls: 80.0)
    assert _first([("K", 75.0, 0.0)], not_yet) == pytest.approx(5.0 / 1.0 - 5.0)  # 5 m before: arrives in 5 s
    assert _first([("K", 75.0, 0.0)], good) == math.inf  # queued at its line for good: it does not come
    assert _first([("K", 50.0, 10.0)], good) == pytest.approx(-2.0)  # one that moves counts as before
    # in the sweep, in the junction, just out of it beside the entry: it holds the ego however long it stands
    assert _first([("K", 85.0, 0.0)], good) == pytest.approx(-5.0)
    assert _first([("I", 3.0, 0.0)], good) == -math.inf
    assert _first([("B", 5.0, 0.0)], good) == -math.inf


def test_the_ego_is_never_in_its_own_way():
    # at a turnaround the lane the ego stands on is its exit's oncoming lane: it does not wait for itself
    assert _first([("K", 85.0, 0.0)], ego_row=0) == math.inf
    assert _first([("K", 85.0, 0.0), ("K", 50.0, 10.0)], ego_row=0) == pytest.approx(-2.0)


def test_oncoming_first_hand_computed():
    assert TURN_CRAWL_MPS == 2.0  # the ego clears in (120 - 110) / 2 = 5 s
    assert _first([]) == math.inf
    assert _first([("L", 50.0, 10.0)]) == pytest.approx(30.0 / 10.0 - 5.0)  # arrives in 3 s: -2 s
    assert _first([("L", 20.0, 5.0)]) == pytest.approx(60.0 / 5.0 - 5.0)  # 12 s: +7 s
    assert _first([("L", 75.0, 0.0)]) == pytest.approx(5.0 / 1.0 - 5.0)  # standing 5 m before: v floor 1 m/s
    assert _first([("L", 85.0, 3.0)]) == pytest.approx(-5.0)  # past the point, still moving: there now
    assert _first([("L", 85.0, 0.0)]) == math.inf  # past the point and standing: may wait for the ego
    assert _first([("K", 85.0, 0.0)]) == pytest.approx(-5.0)  # ... but waits for others: stays in the sweep
    assert _first([("K", 75.0, 0.0)]) == pytest.approx(5.0 / 1.0 - 5.0)  # before the point: as on L
    assert _first([("I", 3.0, 6.0)]) == -math.inf  # crossing the junction
    assert _first([("B", 5.0, 6.0)]) == -math.inf  # just out of it beside the ego's entry
    assert _first([("B", 20.0, 6.0)]) == math.inf  # ... and clear of it


@pytest.fixture(scope="module")
def nets(tmp_path_factory):
    d = tmp_path_factory.mktemp("wide")
    out = {}
    for name in ("t", "t130"):
        shutil.copy(DATA / f"{name}.nod.xml", d / f"{name}.nod.xml")
        subprocess.run([str(BIN / "netconvert"), "-n", str(d / f"{name}.nod.xml"), "-e", str(DATA / "t.edg.xml"),
                        "--no-turnarounds", "true", "--default.junctions.radius", "2", "-o", str(d / f"{name}.net.xml")],
                       check=True, capture_output=True)
        out[name] = d / f"{name}.net.xml"
    return d, out


def _task(net):
    plan = Road.from_net_file(str(net)).route(["AB", "BC"])
    return plan, EgoTask("ego", plan.path[-1], plan.path, 12.0, plan.links, None, plan.lanes, 1.8, 5.0)


@pytest.mark.sumo
def test_wide_exit_found_only_where_the_line_leaves_the_lane(nets):
    _, net = nets
    plan, task = _task(net["t130"])
    (lane, length, side, via, waits), = plan.links[0].oncoming
    assert lane == "CB_0" and side == 1 and via and all(v.startswith(":B_") for v in via)
    assert plan.links[0].leaving == ("BA_0",)
    exits = wide_exits(task, 4.25)
    assert list(exits) == [0]
    (c_lane, c_off, c_waits), = exits[0].conflicts
    assert c_lane == "CB_0" and length - 15.0 < c_off < length  # a few metres before the oncoming lane's end
    assert exits[0].s_clear_m > plan.links[0].s_stop_m
    assert wide_exits(task, 0.0) == {}  # no turning radius, no drivable line
    assert wide_exits(_task(net["t"])[1], 4.25) == {}  # 105 deg: the line keeps inside its lane


def _run(d, net, monkeypatch, hold: bool):
    (d / "w.rou.xml").write_text(
        '<routes>\n  <vType id="car" length="5" width="1.8" accel="2.6" decel="4.5" maxSpeed="20"/>\n'
        '  <vehicle id="ego" type="car" depart="0" departPos="20" departSpeed="10"><route edges="AB BC"/></vehicle>\n'
        '  <vehicle id="onc" type="car" depart="8" departSpeed="13"><route edges="CB BA"/></vehicle>\n</routes>\n')
    (d / "w.toml").write_text(f'name = "wide"\n[sim]\nnet = "{net.name}"\nroutes = ["w.rou.xml"]\nstep_s = 0.1\n'
                              'duration_s = 45.0\nseed = 1\n[ego]\nids = ["ego"]\ncontroller = "apf_sa"\n'
                              'cruise_speed_mps = 12.0\n')
    if not hold:
        monkeypatch.setattr(rules, "wide_exits", lambda task, radius: {})
    return outputs.run_metrics(runner.run(scenario.load(d / "w.toml")))


@pytest.mark.sumo
def test_ego_waits_for_the_oncoming_car_its_wide_exit_would_meet(nets, monkeypatch):
    d, net = nets
    m = _run(d, net["t130"], monkeypatch, hold=True)
    assert m["goal_reached"] and m["collisions"] == 0 and m["rules_yields"] >= 1
    assert m["min_gap_m"] > 0.1
    m = _run(d, net["t130"], monkeypatch, hold=False)  # without the hold the same traffic meets at the exit
    assert m["collisions"] >= 1


@pytest.mark.sumo
def test_a_turnaround_does_not_wait_for_the_ego_s_own_lane(tmp_path):
    # turning round at B (AB -> BA), the exit's oncoming lane is AB_0, the lane the ego comes by: who is on it
    # is ahead of the ego (turning round first) or follows it; it is no conflict (unseen Berlin: an ego waited
    # 370 s at a dead end for the cars queued ahead of it on its own lane)
    (tmp_path / "u.nod.xml").write_text('<nodes><node id="A" x="0" y="0"/><node id="B" x="100" y="0"/></nodes>')
    (tmp_path / "u.edg.xml").write_text('<edges><edge id="AB" from="A" to="B" numLanes="1" speed="13.9"/>'
                                        '<edge id="BA" from="B" to="A" numLanes="1" speed="13.9"/></edges>')
    net = tmp_path / "u.net.xml"  # B a dead end: netconvert gives it a turnaround
    subprocess.run([str(BIN / "netconvert"), "-n", str(tmp_path / "u.nod.xml"), "-e", str(tmp_path / "u.edg.xml"),
                    "-o", str(net)], check=True, capture_output=True)
    plan = Road.from_net_file(str(net)).route(["AB", "BA"])
    assert [o.lane for lk in plan.links for o in lk.oncoming] == ["AB_0"]  # SUMO's view: AB is BA's oncoming lane
    task = EgoTask("ego", plan.path[-1], plan.path, 12.0, plan.links, None, plan.lanes, 1.8, 5.0)
    assert all(c[0] != "AB_0" for w in wide_exits(task, 4.25).values() for c in w.conflicts)

