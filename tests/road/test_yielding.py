"""Right of way: the junction logic read from the net, gap acceptance (pure, pinned by hand), and
a roundabout entry on real SUMO. The roundabout is built here by netconvert from the plain XML in
tests/data/roundabout (ring radius 20 m, four single-lane arms); a circulating vehicle reaches the
south entry about when the ego (APF-SA, 10 m/s) does."""
import math
import pathlib
import shutil
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.runs import outputs
from sumo_avoid.road.route import FoeLink, RouteLink
from sumo_avoid.runs import runner
from sumo_avoid.safety.traffic import RulesParams
from sumo_avoid.road.yielding import (
    arrival_time,
    can_give_way,
    critical_gap_s,
    ego_time_to_line,
    foe_arrival,
    foe_arrivals,
    link_state,
    rows_by_lane,
    stand_run,
    waits_its_turn,
    yields,
    zipper_slot,
)
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.road.network import Road

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
DATA = pathlib.Path(__file__).parent.parent / "data"


def test_link_state_and_who_yields():
    minor = RouteLink(100.0, "J", state="m", foes=(FoeLink(state="M"),))
    assert yields(minor, {}) and link_state({}, "", -1, "m") == "m"
    assert not yields(RouteLink(100.0, "J", state="M", foes=(FoeLink(),)), {})  # major: never
    assert not yields(RouteLink(100.0, "J", state="m"), {})  # no foes
    signalled = RouteLink(100.0, "J", tls="T", link_index=1, state="o", foes=(FoeLink(),))
    assert yields(signalled, {"T": "GgG"})  # permissive green
    assert not yields(signalled, {"T": "GGG"}) and not yields(signalled, {"T": "rrr"})  # major green; red is the signal's
    p = RulesParams()  # 4.5 s, 5 s left, 1 s zipper
    assert [critical_gap_s(RouteLink(0.0, "J", state="m", direction=d), p) for d in "ltsr"] == [5.0, 5.0, 4.5, 4.5]
    assert critical_gap_s(RouteLink(0.0, "J", state="Z", direction="s"), p) == 1.0


def test_zipper_slot_by_hand():
    h = 2.0
    assert zipper_slot(3.0, [], h) == 3.0  # nobody: now
    assert zipper_slot(3.0, [0.5, 5.5], h) == 3.0  # 2.5 s after one and before the next
    assert zipper_slot(3.0, [2.0, 4.5], h) == 6.5  # 2.0 and 4.5 too close: behind the second
    assert zipper_slot(3.0, [2.0, 4.0, 7.0, 9.5], h) == 11.5  # 6.0 is 1 s before 7.0, 9.0 0.5 s before 9.5
    # a foe behind the slot that can give way lets the ego in; one ahead of it never does
    assert zipper_slot(3.0, [2.0, 4.5], h, [False, True]) == 4.0  # 2 s behind the first, the second lets it in
    assert zipper_slot(3.0, [2.0, 4.5], h, [True, False]) == 6.5  # the first is ahead: giving way does not apply
    assert zipper_slot(3.0, [3.5], h, [True]) == 3.0  # arrives after the ego: lets it in now
    assert zipper_slot(3.0, [2.5], h, [True]) == 4.5  # arrives before the ego: it goes first


def test_can_give_way_by_hand():
    # 10 m/s at 3 m/s^2 needs 100 / 6 = 16.67 m
    assert can_give_way([16.7, 16.6, 0.0], [10.0, 10.0, 0.0], 3.0).tolist() == [True, False, True]


def test_foe_arrival_by_hand():
    # foe link: conflict 10 m into internal lane ":J_1_0"; its incoming lane "a_0" is 100 m long
    foe = FoeLink(state="M", approach=((":J_1_0", 10.0), ("a_0", 110.0)))
    lanes = rows_by_lane(["a_0", ":J_1_0", "", "a_0"])
    lane_pos = np.array([80.0, 4.0, np.nan, 20.0])
    speed = np.array([10.0, 0.5, 0.0, 15.0])
    length = np.full(4, 5.0)
    # row 0: (110 - 80) / 10 = 3.0 s; row 1: (10 - 4) / max(0.5, 1) = 6.0 s; row 3: 90 / 15 = 6.0 s
    t, who = foe_arrival((foe,), {}, lanes, lane_pos, speed, length, set())
    assert (t, who) == (pytest.approx(3.0), 0)
    t, who = foe_arrival((foe,), {}, lanes, lane_pos, speed, length, {0})  # the ego itself is excluded
    assert (t, who) == (pytest.approx(6.0), 1)
    passed = np.array([80.0, 14.9, np.nan, 20.0])  # 4.9 m past the conflict with 5 m length: still in it
    assert foe_arrival((foe,), {}, lanes, passed, speed, length, {0, 3}) == (0.0, 1)
    gone = np.array([80.0, 15.1, np.nan, 20.0])  # clear of it
    assert foe_arrival((foe,), {}, lanes, gone, speed, length, {0, 3}) == (math.inf, -1)
    red = FoeLink(tls="T", link_index=0, state="M", approach=foe.approach)
    assert foe_arrival((red,), {"T": "r"}, lanes, lane_pos, speed, length, set()) == (math.inf, -1)
    assert ego_time_to_line(21.0, 10.0, 1.0) == pytest.approx(2.0)
    assert ego_time_to_line(5.0, 0.0, 1.0) == pytest.approx(4.0)  # standing: 1 m/s floor


def test_junction_logic_from_the_net():
    """left_turn net: the ego's left turn S2C -> C2W (minor 'm') yields to the oncoming N2C
    straight links (major 'M'), and only to them; their approach starts at N2C's lanes."""
    road = Road.from_net_file(DATA.parent.parent / "nets" / "left_turn.net.xml")
    (link,) = road.route(["S2C", "C2W"], depart_lane=1).links
    assert link.state == "m" and link.direction == "l"
    assert [(f.state, f.direction) for f in link.foes] == [("M", "s"), ("M", "s")]
    for f in link.foes:
        lanes = dict(f.approach)
        assert {ln.split("_")[0] for ln in lanes if not ln.startswith(":")} == {"N2C"}
        internal = [v for k, v in lanes.items() if k.startswith(":")]
        assert len(internal) == 1 and 0.0 < internal[0] < 25.0  # conflict inside the junction


@pytest.fixture(scope="module")
def roundabout(tmp_path_factory):
    d = tmp_path_factory.mktemp("rb")
    for f in ("rb.nod.xml", "rb.edg.xml"):
        shutil.copy(DATA / "roundabout" / f, d / f)
    subprocess.run([str(BIN / "netconvert"), "-n", str(d / "rb.nod.xml"), "-e", str(d / "rb.edg.xml"),
                    "--no-turnarounds", "true", "-o", str(d / "rb.net.xml")], check=True, capture_output=True)
    (d / "rb.rou.xml").write_text(
        '<routes>\n  <vType id="car" length="4.5" width="1.8" accel="2.6" decel="4.5" maxSpeed="20"/>\n'
        '  <vehicle id="circ" type="car" depart="0" departPos="40" departSpeed="10">'
        '<route edges="W_in ring_WS ring_SE E_out"/></vehicle>\n'
        '  <vehicle id="ego" type="car" depart="0" departPos="20" departSpeed="10">'
        '<route edges="S_in ring_SE ring_EN N_out"/></vehicle>\n</routes>\n')
    return d


def _scenario(d, rules):
    f = d / f"rb_{rules}.toml"
    f.write_text('name = "rb"\n[sim]\nnet = "rb.net.xml"\nroutes = ["rb.rou.xml"]\nstep_s = 0.1\nduration_s = 45.0\n'
                 f'seed = 1\n[ego]\nids = ["ego"]\ncontroller = "apf_sa"\ncruise_speed_mps = 10.0\nlayers = {[] if rules == "none" else [rules]}\n')
    return scenario.load(f)


def _run(d, rules):
    return outputs.run_metrics(runner.run(_scenario(d, rules)))


@pytest.fixture(scope="module")
def with_rules(roundabout):
    """The run with the traffic-rules layer, shared by the two tests that assert on it."""
    res = runner.run(_scenario(roundabout, "traffic"))
    return res, outputs.run_metrics(res)


@pytest.mark.sumo
def test_roundabout_entry_waits_for_the_circulating_vehicle(with_rules):
    _, m = with_rules
    (entry,) = m["yield_crossings"]
    assert entry["junction"] == "rS" and entry["state"] == "m"
    assert m["rules_yields"] == 1 and m["yield_violations"] == 0
    assert entry["foe"] in ("", "circ") and (entry["foe_arrival_s"] is None or entry["foe_arrival_s"] > 4.5)
    assert m["collisions"] == 0 and m["sumo_collisions"] == 0 and m["goal_reached"]
    assert m["phi_wall"] == 0.0


@pytest.mark.sumo
def test_without_the_rules_layer_the_ego_cuts_in_and_the_metric_says_so(roundabout):
    m = _run(roundabout, "none")
    (entry,) = m["yield_crossings"]
    assert entry["violation"] and entry["foe"] == "circ" and entry["foe_arrival_s"] < 4.5
    assert m["yield_violations"] == 1


@pytest.mark.sumo
def test_sumo_sees_the_waiting_ego_on_its_entry_lane_not_on_the_ring(with_rules):
    """Placement on the route (moveToXY keepRoute=1): while the ego waits at the entry, SUMO has it
    on the entry lane, so the circulating car is not held up by a phantom on the ring."""
    res, _ = with_rules
    t = res.traj
    ego, circ = t[t["id"] == "ego"], t[t["id"] == "circ"]
    waiting = ego[(ego["speed"] < 2.0) & (ego["time_s"] > 5.0) & (ego["time_s"] < 13.0)]  # slowed at the entry
    assert len(waiting) > 5 and set(waiting["lane"]) == {"S_in_0"}
    assert circ["speed"].min() > 3.0
    assert [ln for ln in dict.fromkeys(ego["lane"]) if not ln.startswith(":")] == ["S_in_0", "ring_SE_0", "ring_EN_0", "N_out_0"]
    route_edges = {p.edge for p in res.tasks["ego"].lanes}  # internal lanes of its own links included
    assert {ln.rsplit("_", 1)[0] for ln in ego["lane"].dropna()} <= route_edges


def test_all_way_stop_first_come_first_served_by_hand():
    """yielding.waits_its_turn: (to_line, x, v, now, ego first stood at, history(row) -> (start, end))."""
    standing_since = lambda start: (lambda r: (start, math.nan))  # noqa: E731
    assert waits_its_turn(1.0, 12.0, 0.0, 30.0, 20.0, standing_since(25.0), 0)  # came after the ego: waits
    assert not waits_its_turn(1.0, 12.0, 0.0, 30.0, 20.0, standing_since(15.0), 0)  # came first: goes
    assert waits_its_turn(8.0, 19.0, 0.0, 30.0, 20.0, standing_since(5.0), 0)  # queued 8 m behind its line
    never = lambda r: (math.nan, math.nan)  # noqa: E731
    # braking into its line: 6.45^2 / (2 * 4.5) = 4.62 m <= 16.1 m to the conflict point -> stops first
    assert waits_its_turn(4.4, 16.1, 6.45, 84.2, 80.0, never, 0)
    # the same car having set off from its line 2 s ago is crossing
    assert not waits_its_turn(4.4, 16.1, 6.45, 84.2, 80.0, lambda r: (70.0, 82.2), 0)
    # too fast to stop before the conflict point: 14^2 / 9 = 21.8 m > 10 m
    assert not waits_its_turn(2.0, 10.0, 14.0, 84.2, 80.0, never, 0)
    # the ego has not stood yet (first = inf): a car standing at its line goes first
    assert not waits_its_turn(0.5, 10.0, 0.0, 30.0, math.inf, standing_since(29.0), 0)


def test_arrival_times_and_standing_runs_by_hand():
    assert arrival_time(8.0, 0.0) == 8.0  # x / max(v, 1 m/s)
    assert arrival_time(8.0, 4.0) == 2.0
    assert arrival_time(13.0, 0.0, starting=True) == pytest.approx(math.sqrt(10.0))  # sqrt(2 x / 2.6)
    assert arrival_time(5.2, 2.6, starting=True) == pytest.approx((math.sqrt(2.6**2 + 2 * 2.6 * 5.2) - 2.6) / 2.6)
    t = [0.0, 1.0, 2.0, 3.0, 4.0]
    assert stand_run(t, [5, 0, 0, 3, 3]) == (1.0, 3.0)
    s, e = stand_run(t, [5, 0, 0, 3, 0])
    assert s == 4.0 and math.isnan(e)
    assert stand_run(t, [0, 0, 0, 0, 0])[0] == 0.0
    assert all(math.isnan(v) for v in stand_run(t, [1, 2, 3, 4, 5]))


def test_a_slow_foe_at_its_stop_line_is_setting_off():
    """On a signalised link, within 5 m of its line (line_m = 10 m before the conflict point) and
    slower than 5 m/s: a standing start; farther back, or unsignalised: constant speed (x / max(v, 1 m/s))."""
    lanes = {"a_0": [0]}
    def first(state, lane_pos, v):  # noqa: E306
        foe = FoeLink(tls="" if state == "Z" else "T", link_index=0, state=state, approach=(("a_0", 100.0),), line_m=10.0)
        return foe_arrival((foe,), {}, lanes, np.array([lane_pos]), np.array([v]), np.array([5.0]), set())[0]
    assert first("M", 88.0, 2.0) == pytest.approx((math.sqrt(4.0 + 2 * 2.6 * 12.0) - 2.0) / 2.6)  # 3 m before its line
    assert first("M", 70.0, 2.0) == pytest.approx(15.0)  # 20 m before it: 30 m / 2 m/s
    assert first("M", 88.0, 6.0) == pytest.approx(2.0)  # not slow: 12 m / 6 m/s
    assert first("Z", 88.0, 2.0) == pytest.approx(6.0)  # unsignalised (a zipper): 12 m / 2 m/s


def test_on_yellow_a_foe_that_can_stop_comfortably_at_its_line_is_not_waited_for():
    # the conflict point 20 m past the foe link's stop line; three foes at 12 m/s: 44 m before the line
    # (stops braking at 1.6 m/s^2), 14 m before it (needs 5.1 m/s^2 > 3: goes on), 5 m past it
    foe = FoeLink(tls="T", link_index=0, state="o", approach=(("a", 100.0),), line_m=20.0)
    lanes = {"a": [0, 1, 2]}
    pos = np.array([100.0 - 64.0, 100.0 - 34.0, 100.0 - 15.0])
    v = np.full(3, 12.0)
    go = foe_arrivals((foe,), {"T": "G"}, lanes, pos, v, np.full(3, 4.5), set())
    assert sorted(r for _, r, _ in go) == [0, 1, 2]
    yellow = foe_arrivals((foe,), {"T": "y"}, lanes, pos, v, np.full(3, 4.5), set())
    assert sorted(r for _, r, _ in yellow) == [1, 2]
    assert foe_arrivals((foe,), {"T": "r"}, lanes, pos, v, np.full(3, 4.5), set()) == []


def test_a_signalised_turn_gives_way_at_its_internal_junction():
    assert RouteLink(100.0, "J", tls="T", link_index=1, state="o", s_wait_m=109.0).yield_line_m == 109.0
    assert RouteLink(100.0, "J", state="m", s_wait_m=109.0).yield_line_m == 100.0  # unsignalised: the stop line
    assert RouteLink(100.0, "J", tls="T", link_index=1, state="o").yield_line_m == 100.0  # none (nan)


def test_a_vehicle_moving_in_the_junction_arrives_one_standing_there_does_not():
    """clearing_arrivals by hand: a link inside with its internal lane ":J_3_0" (conflict 8 m from its
    start). Row 0 moves at 4 m/s 2 m in: setting off (slower than START_MPS), (sqrt(16 + 2 * 2.6 * 6) - 4)
    / 2.6 = 1.0475 s; row 1 stands at its internal stop (waits for the ego); row 2 at 10 m/s is 1 m past
    the conflict, less than its 4.5 m: 0 s; row 3 is 5 m past it: gone."""
    from sumo_avoid.road.yielding import clearing_arrivals

    inside = (FoeLink(state="m", approach=((":J_3_0", 8.0),), line_m=8.0),)
    lanes = rows_by_lane([":J_3_0"] * 4)
    got = clearing_arrivals(inside, lanes, np.array([2.0, 3.0, 9.0, 13.0]), np.array([4.0, 0.0, 10.0, 10.0]),
                            np.full(4, 4.5), set())
    assert got == pytest.approx([(math.sqrt(16.0 + 2.0 * 2.6 * 6.0) - 4.0) / 2.6, 0.0])
    assert clearing_arrivals(inside, lanes, np.array([2.0, 3.0, 9.0, 13.0]), np.array([4.0, 0.0, 10.0, 10.0]),
                             np.full(4, 4.5), {0}) == [0.0]
