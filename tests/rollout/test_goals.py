"""Goals given as edge ids and per ego ([ego.goals]), and egos that never depart: real libsumo on the
left_turn crossroads (nets/left_turn.net.xml; S2C comes from the south, C2W leaves to the west)."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.road.network import Road
from tests.conftest import ROOT, SCENARIOS

NET = ROOT / "nets" / "left_turn.net.xml"


def _scenario(tmp_path, routes: str, ego: str, duration_s: float = 40.0):
    (tmp_path / "r.rou.xml").write_text(f"<routes>\n{routes}\n</routes>\n")
    path = tmp_path / "s.toml"
    path.write_text(f'name = "goals"\n[sim]\nnet = "{NET}"\nroutes = ["r.rou.xml"]\nduration_s = {duration_s}\n'
                    f'[ego]\ncruise_speed_mps = 10.0\n{ego}\n')
    return path


CARS = """  <vType id="car" length="4.5" width="1.8" sigma="0"/>
  <vehicle id="ego" type="car" depart="0" departLane="1" departPos="150" departSpeed="10"><route edges="S2C C2W"/></vehicle>
  <vehicle id="ego2" type="car" depart="0" departLane="0" departPos="120" departSpeed="10"><route edges="S2C C2N"/></vehicle>"""


@pytest.mark.sumo
def test_edge_goals_per_ego_are_where_each_route_path_leaves_the_edge(tmp_path):
    """ego: goal edge S2C = the stop line of its left-turn lane (S2C_1) at the junction, reached
    long before the end of its route; ego2 (per-ego table): goal edge C2N, its route's last edge =
    the end of its route; ego3 (no entry in [ego.goals]) takes ego.goal, a point."""
    extra = '  <vehicle id="ego3" type="car" depart="0" departLane="1" departPos="100" departSpeed="10"><route edges="S2C C2W"/></vehicle>'
    path = _scenario(tmp_path, CARS + "\n" + extra,
                     'ids = ["ego", "ego2", "ego3"]\ngoal = [-100.0, 1.6]\n[ego.goals]\nego = "S2C"\nego2 = "C2N"')
    res = runner.run(scenario.load(path))
    road = Road.from_net_file(NET)
    stop_line = road.lane_shape("S2C", 1)[-1]
    assert np.allclose(res.goals["ego"], stop_line, atol=1e-6)
    assert np.allclose(res.goals["ego2"], road.route_path(["S2C", "C2N"], depart_lane=0)[-1], atol=1e-6)
    assert res.goals["ego3"] == (-100.0, 1.6)
    ego = res.traj[res.traj["id"] == "ego"]
    last = ego[["x", "y"]].to_numpy()[-1]
    assert np.hypot(*(last - stop_line)) <= 5.0  # retired at its goal edge's end ...
    assert ego["time_s"].max() < 12.0  # ... after ~100 m, not at the end of C2W (250 m further)
    assert set(res.traj.loc[res.traj["is_ego"], "id"]) == {"ego", "ego2", "ego3"}


@pytest.mark.sumo
def test_a_goal_edge_off_the_route_sumo_gave_the_ego_is_a_scenario_error(tmp_path):
    path = _scenario(tmp_path, CARS, 'ids = ["ego", "ego2"]\n[ego.goals]\nego2 = "C2W"')
    with pytest.raises(ScenarioError) as e:
        runner.run(scenario.load(path))
    assert str(e.value) == (f"{path}: key 'ego.goals.ego2': expected an edge on the route SUMO gave ego 'ego2' "
                            f"(S2C C2N), got 'C2W'")


def test_goal_edges_and_per_ego_goals_are_checked_on_load(tmp_path):
    cases = {'goal = "nowhere"': ("ego.goal", "an edge id of the network"),
             'goal = ":C_0"': ("ego.goal", "an edge id of the network"),  # internal edges are not goals
             '[ego.goals]\nnobody = "S2C"': ("ego.goals.nobody", "an ego id"),
             '[ego.goals]\nego = [1.0]': ("ego.goals.ego", "[x, y] or an edge id"),
             '[ego.goals]\nego = 3': ("ego.goals.ego", "a list of a number or a string"),
             '[ego.goals]\nego = [500.0, 500.0]': ("ego.goals.ego", "drivable area")}
    for text, (key, expected) in cases.items():
        path = _scenario(tmp_path, CARS, f'ids = ["ego"]\n{text}')
        with pytest.raises(ScenarioError) as e:
            scenario.load(path)
        assert f"key '{key}'" in str(e.value) and expected in str(e.value), (text, str(e.value))
    good = scenario.load(_scenario(tmp_path, CARS, 'ids = ["ego"]\ngoal = "C2W"\n[ego.goals]\nego = [-100, 1.6]'))
    assert good.spec.ego.goal == "C2W" and good.spec.ego.goals == {"ego": (-100.0, 1.6)}
    over = scenario.load(SCENARIOS / "left_turn.toml", ['ego.goals.ego="S2C"'])
    assert over.spec.ego.goals == {"ego": "S2C"}


@pytest.mark.sumo
def test_an_ego_that_never_departs_is_a_scenario_error_naming_it_and_why(tmp_path):
    """'late' departs after the end; 'blocked' cannot be inserted (a car stands where it would
    depart, with SUMO's insertion checks on): the run is an error, not a silent run."""
    routes = CARS + """
  <vehicle id="parked" type="car" depart="0" departLane="0" departPos="60" departSpeed="0"><route edges="W2C C2E"/><stop lane="W2C_0" endPos="60" duration="1000"/></vehicle>
  <vehicle id="blocked" type="car" depart="1" departLane="0" departPos="60"><route edges="W2C C2E"/></vehicle>
  <vehicle id="late" type="car" depart="500"><route edges="S2C C2W"/></vehicle>"""
    path = _scenario(tmp_path, routes, 'ids = ["ego", "blocked"]', duration_s=5.0)
    with pytest.raises(ScenarioError) as e:
        runner.run(scenario.load(path))
    assert str(e.value).startswith(f"{path}: key 'ego.ids[1]': expected egos that depart within the run: 'blocked' "
                                   "never departed by t=5.0 s (SUMO could not insert it")
    path = _scenario(tmp_path, routes, 'ids = ["ego", "late"]', duration_s=5.0)  # found from its depart time
    with pytest.raises(ScenarioError, match=r"'ego.ids\[1\]'.*'late' departs at t=500 s, the run ends at sim.duration_s"):
        scenario.load(path)
