"""Streets too narrow for two cars (safety/narrow_streets.py): the ego waits before one while a car comes
the other way on it.

Real SUMO: tests/data/narrow, built here with netconvert: a street of one 3.2 m lane each way (A-B, 100 m)
going on as one of 1.6 m lanes (B-C, 150 m), as netconvert draws OSM residential streets with width tags
(unseen Berlin Adlershof). An ego drives A-B-C while a car comes C-B-A: on B-C the two, 1.8 m wide, overlap
by 0.4 m on their lanes' centres."""
import dataclasses
import pathlib
import shutil
import subprocess

import pytest
import sumo

from sumo_avoid.road.network import Road
from sumo_avoid.runs import outputs, runner
from sumo_avoid.safety import traffic as rules
from sumo_avoid.safety.narrow_streets import NARROW_MARGIN_M, narrow_stretches
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.core.types import EgoTask

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
DATA = pathlib.Path(__file__).parent.parent / "data" / "narrow"


@pytest.fixture(scope="module")
def net(tmp_path_factory):
    d = tmp_path_factory.mktemp("narrow")
    for f in ("n.nod.xml", "n.edg.xml"):
        shutil.copy(DATA / f, d / f)
    subprocess.run([str(BIN / "netconvert"), "-n", str(d / "n.nod.xml"), "-e", str(d / "n.edg.xml"),
                    "--no-turnarounds", "true", "-o", str(d / "n.net.xml")], check=True, capture_output=True)
    return d


def test_the_narrow_stretch_of_a_route(net):
    plan = Road.from_net_file(str(net / "n.net.xml")).route(["AB", "BC"], vclass="passenger")
    task = EgoTask("ego", plan.path[-1], plan.path, 12.0, plan.links, None, plan.lanes, 1.8, 5.0)
    (st,) = narrow_stretches(task)  # A-B: 3.2 + 3.2 m, room for two; B-C: 1.6 + 1.6 < 2 x 1.8 + 0.4
    bc = next(p for p in plan.lanes if p.edge == "BC")
    assert NARROW_MARGIN_M == 0.4
    assert st.s_start_m == bc.s_start_m and st.s_end_m == bc.s_end_m and st.room_m == pytest.approx(3.2)
    assert st.inside == (("CB_0", bc.s_end_m),) and st.beyond == ()
    wide = dataclasses.replace(task, width_m=1.3)  # 2 x 1.3 + 0.4 = 3.0 < 3.2: two such cars pass
    assert narrow_stretches(wide) == ()


def _run(d, monkeypatch, rule: bool):
    (d / "n.rou.xml").write_text(
        '<routes>\n  <vType id="car" length="5" width="1.8" accel="2.6" decel="4.5" maxSpeed="20"/>\n'
        '  <vehicle id="ego" type="car" depart="0" departPos="10" departSpeed="10"><route edges="AB BC"/></vehicle>\n'
        '  <vehicle id="onc" type="car" depart="2" departSpeed="10"><route edges="CB BA"/></vehicle>\n</routes>\n')
    (d / "n.toml").write_text('name = "narrow"\n[sim]\nnet = "n.net.xml"\nroutes = ["n.rou.xml"]\nstep_s = 0.1\n'
                              'duration_s = 40.0\nseed = 1\n[ego]\nids = ["ego"]\ncontroller = "apf_sa"\n'
                              'cruise_speed_mps = 12.0\n')
    if not rule:
        monkeypatch.setattr(rules, "narrow_stretches", lambda task: ())
    return outputs.run_metrics(runner.run(scenario.load(d / "n.toml")))


@pytest.mark.sumo
def test_the_ego_waits_before_a_narrow_street_for_the_oncoming_car(net, monkeypatch):
    m = _run(net, monkeypatch, rule=True)
    assert m["goal_reached"] and m["collisions"] == 0 and m["rules_yields"] >= 1 and m["min_gap_m"] > 0.3
    m = _run(net, monkeypatch, rule=False)  # without the rule the two meet on it
    assert m["collisions"] >= 1


def test_an_edge_the_path_blends_across_is_one_oncoming_lane_starting_at_its_end():
    """Hand-made pieces: a 1.6 m edge 'n' (s 0-100, oncoming 1.6 m), a junction, then a two-lane edge 'w'
    the path blends across in two pieces (s 105-115, 115-200): its oncoming lane starts at s = 200, not at
    the blend's end."""
    from types import SimpleNamespace

    from sumo_avoid.road.route import LanePiece

    n = LanePiece(0.0, 100.0, "n", 0, (0.0,), (0.0,), (1.6,), (True,), 1.6, "on_0")
    j = LanePiece(100.0, 105.0, ":j_0", 0, (0.0,), (0.0,), (3.2,))
    w1 = LanePiece(105.0, 115.0, "w", 1, (3.2, 0.0), (0.0, -3.2), (3.2, 3.2), (True, True), 3.2, "ow_0")
    w2 = LanePiece(115.0, 200.0, "w", 1, (0.0, -3.2), (0.0, -3.2), (3.2, 3.2), (True, True), 3.2, "ow_0")
    (st,) = narrow_stretches(SimpleNamespace(lanes=(n, j, w1, w2), width_m=1.8))
    assert (st.s_start_m, st.s_end_m, st.room_m) == (0.0, 100.0, 3.2)
    assert st.inside == (("on_0", 100.0),) and st.beyond == (("ow_0", 200.0),)
