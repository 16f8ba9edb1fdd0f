"""The city suite (issue 34 item 4; scenarios/cities/README.md): three districts read from ../shared/cities/, each
run as its own SUMO configuration gives it, at least three ego routes per district through at least four junctions,
an APF-SA entry with the acceptance criteria and a SUMO-driver entry per route in scenarios/cities.toml. SUMO loads
each scenario and the ego departs on its route (a run of 2 s begun at the ego's depart time)."""
import importlib.util
import tomllib
import xml.etree.ElementTree as ET

import pytest
from conftest import ROOT, SCENARIOS

from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import suite

CITIES = ROOT.parent / "shared" / "cities"
FOLDER = SCENARIOS / "cities"
PATHS = sorted(FOLDER.glob("*.toml"))
pytestmark = pytest.mark.skipif(not CITIES.is_dir(), reason="../shared/cities is not beside the checkout")
ACCEPTANCE = {"goal_reached_rate >= 0.95", "collisions == 0", "sumo_ego_collisions == 0", "vru_collisions == 0",
              "red_light_violations == 0", "yield_violations == 0", "stop_sign_violations == 0", "off_road_m == 0",
              "phi_wall <= 0.1", "travel_time_ratio_median <= 1.5"}
CONFIGS = {"bologna": "bologna_acosta/run.sumocfg", "berlin": "berlin_doerpfeldstr/all_modes.sumocfg",
           "wildau": "wildau/flow1_Spaet.sumocfg"}


def _routes_module():
    spec = importlib.util.spec_from_file_location("city_routes", FOLDER / "routes.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _ego(path):
    sim = tomllib.loads(path.read_text())["sim"]
    ego, = [v for v in ET.parse(path.parent / sim["routes"][-1]).getroot().iter("vehicle") if v.get("id") == "ego"]
    return ego


def test_three_districts_each_with_three_routes_run_from_their_own_configuration():
    by_city = {}
    for path in PATHS:
        by_city.setdefault(path.stem.split("_")[0], []).append(path)
        sim = tomllib.loads(path.read_text())["sim"]
        city = path.stem.split("_")[0]
        assert (path.parent / sim["sumocfg"]).resolve() == (CITIES / CONFIGS[city]).resolve()
        for f in sim["routes"][:-1] + sim.get("additional", []):  # the district's files, read where they are
            assert f.startswith("../../../shared/cities/") and (path.parent / f).is_file()
    assert {c: len(p) for c, p in by_city.items()} == {"berlin": 3, "bologna": 3, "wildau": 3}
    assert not [p for p in FOLDER.rglob("*") if p.name.endswith((".net.xml", ".net.xml.gz", ".sumocfg"))]


def test_each_ego_route_is_connected_for_a_car_through_four_junctions():
    routes, nets = _routes_module(), {}
    for path in PATHS:
        net_file, edges = routes.ego_route(path)
        if net_file not in nets:
            nets[net_file] = routes.read_net(net_file)
        assert len(routes.junctions(nets[net_file], edges)) >= 4, path.stem  # raises where a link is missing


def test_the_suite_has_apf_sa_with_the_acceptance_and_sumo_per_route():
    entries = suite.load(SCENARIOS / "cities.toml")
    suite.check_criteria(entries, "cities.toml")
    for ctrl in ("apf_sa", "sumo"):
        mine = [e for e in entries if e.controller == ctrl]
        assert sorted(e.scenario.resolve() for e in mine) == [p.resolve() for p in PATHS]
    for e in entries:
        text = {c.text for c in e.criteria}
        assert ACCEPTANCE <= text if e.controller == "apf_sa" else text == {"goal_reached_rate >= 0.95"}, e.name


@pytest.mark.sumo  # SUMO loads the district with the scenario's files; the ego departs on its route
@pytest.mark.parametrize("path", PATHS, ids=[p.stem for p in PATHS])
def test_the_ego_departs_on_its_route(path):
    depart = float(_ego(path).get("depart"))
    scn = scenario.load(path, [f"sim.begin_s={depart}", "sim.duration_s=2", "output.plots=false"], controller="sumo")
    res = runner.run(scn)
    ego = res.traj[res.traj["id"] == "ego"]
    assert len(ego) > 0 and ego["time_s"].min() <= depart + 0.2
    routes = _routes_module()
    net_file, edges = routes.ego_route(path)
    passed = {link.junction for link in res.tasks["ego"].links}
    assert {j["node"] for j in routes.junctions(routes.read_net(net_file), edges)} <= passed
