"""No waiting for ever (road.yielding.stands_for_good): a foe with priority standing at its line for
``standing_foe_wait_s`` no longer holds the ego; a moving one still does. By hand, then on real SUMO:
a priority junction built here by netconvert from tests/data/standing_foe (a compact junction,
corner radius 1 m, so that a car standing at the major road's line is 5.8 m from the ego's path and,
at 1 m/s, arrives within HCM's critical headway for crossing from the minor road, 6.5 s, SPEC §5)."""
import math

import numpy as np
import pytest

from sumo_avoid.road.regulation import RulesParams
from sumo_avoid.road.route import FoeLink
from sumo_avoid.road.yielding import STAND_MPS, foe_arrivals, rows_by_lane, stands_for_good
from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario
from tests.conftest import netconvert


def test_a_foe_standing_at_its_line_for_good_by_hand():
    wait = RulesParams().standing_foe_wait_s
    assert wait == 30.0
    since = lambda start, light=-math.inf: (lambda r, tls: max(start, light if tls else -math.inf))  # noqa: E731
    assert stands_for_good(0.5, 0.0, 100.0, wait, since(70.0), 0, "")  # stood 30 s at its line
    assert not stands_for_good(0.5, 0.0, 100.0, wait, since(70.1), 0, "")  # 29.9 s
    assert not stands_for_good(0.5, STAND_MPS, 100.0, wait, since(0.0), 0, "")  # moving (creeping)
    assert not stands_for_good(-1.5, 0.0, 100.0, wait, since(0.0), 0, "")  # inside the junction
    assert stands_for_good(12.0, 0.0, 100.0, wait, since(0.0), 0, "")  # queued behind its line
    assert not stands_for_good(0.5, 0.0, 100.0, wait, since(0.0, 80.0), 0, "T")  # its light changed 20 s ago
    # foe_arrivals leaves it out, and only it: conflict 6 m into the junction, lane "a_0" 100 m long
    foe = FoeLink(state="M", approach=((":J_1_0", 6.0), ("a_0", 106.0)), line_m=6.0)
    lanes = rows_by_lane(["a_0", "a_0"])
    lane_pos, speed, length = np.array([99.5, 60.0]), np.array([0.0, 10.0]), np.full(2, 4.5)
    standing = (100.0, wait, since(70.0))
    assert [r for _, r, _ in foe_arrivals((foe,), {}, lanes, lane_pos, speed, length, set())] == [0, 1]
    assert [r for _, r, _ in foe_arrivals((foe,), {}, lanes, lane_pos, speed, length, set(), None, standing)] == [1]
    # at an all-way stop or a link of equal rank it may be waiting for the ego itself: it still counts
    for state in "w=":
        other = FoeLink(state=state, approach=foe.approach, line_m=6.0)
        assert [r for _, r, _ in foe_arrivals((other,), {}, lanes, lane_pos, speed, length, set(), None,
                                              standing)] == [0, 1]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The foe stands at the major road's line for good (a 1000 s stop at its lane's end), or drives
    through as the ego arrives; the ego (APF-SA, 10 m/s) crosses from the minor road."""
    d = tmp_path_factory.mktemp("standing_foe")
    netconvert("standing_foe", d, "x", "--default.junctions.radius", "1")
    car = '<vType id="car" length="4.5" width="1.8" accel="2.6" decel="4.5" maxSpeed="13"/>'
    ego = '<vehicle id="ego" type="car" depart="0" departPos="140" departSpeed="10"><route edges="SC CN"/></vehicle>'
    foes = {"standing": '<vehicle id="foe" type="car" depart="0" departPos="150" departSpeed="5"><route edges="WC CE"/>'
                        '<stop lane="WC_0" endPos="195.8" duration="1000"/></vehicle>',
            "moving": '<vehicle id="foe" type="car" depart="0" departPos="120" departSpeed="10">'
                      '<route edges="WC CE"/></vehicle>'}
    out = {}
    for name, foe in foes.items():
        (d / f"{name}.rou.xml").write_text(f"<routes>\n  {car}\n  {foe}\n  {ego}\n</routes>\n")
        f = d / f"{name}.toml"
        f.write_text(f'name = "{name}"\n[sim]\nnet = "x.net.xml"\nroutes = ["{name}.rou.xml"]\nstep_s = 0.1\n'
                     'duration_s = 80.0\nseed = 1\n[ego]\nids = ["ego"]\ncontroller = "apf_sa"\ncruise_speed_mps = 10.0\n'
                     '[layers.traffic]\ncritical_gap_s = 6.5\n')
        res = runner.run(scenario.load(f))
        out[name] = (res, outputs.run_metrics(res))
    return out


@pytest.mark.sumo
def test_the_ego_waits_a_bounded_time_for_a_foe_standing_for_good_then_goes(runs):
    res, m = runs["standing"]
    t = res.traj
    ego, foe = t[t["id"] == "ego"], t[t["id"] == "foe"]
    assert foe["speed"].iloc[-1] == 0.0 and foe["lane"].iloc[-1] == "WC_0"  # it never moves again
    stood = ego.loc[ego["speed"] < 0.5, "time_s"]
    foe_stood = float(foe.loc[foe["speed"] < STAND_MPS, "time_s"].min())
    assert stood.min() < foe_stood + 5.0  # held for it ...
    assert 25.0 <= stood.max() - foe_stood <= 35.0  # ... for about standing_foe_wait_s, then gone
    assert m["goal_reached"] and m["collisions"] == 0 and m["sumo_collisions"] == 0
    assert m["rules_yields"] == 1 and m["yield_violations"] == 0
    (crossing,) = m["yield_crossings"]
    assert crossing["foe"] == "" and not crossing["violation"]  # the metric judges it as the layer did


@pytest.mark.sumo
def test_a_moving_foe_still_holds_the_ego(runs):
    res, m = runs["moving"]
    t = res.traj
    ego = t[t["id"] == "ego"]
    (crossing,) = m["yield_crossings"]
    assert ego.loc[ego["time_s"] < crossing["time_s"], "speed"].min() < 3.0  # it slowed for the foe
    assert m["rules_yields"] == 1 and m["yield_violations"] == 0 and not crossing["violation"]
    assert m["goal_reached"] and m["collisions"] == 0 and m["sumo_collisions"] == 0
