"""The streets scenario library (scenarios/streets/): the committed nets are what their plain-XML sources build,
the nets have the lanes and crossings the scenarios promise, every scenario loads and is in the suite, and each
district ego route is connected for a car and passes at least four junctions."""
import importlib.util
import pathlib
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest
import sumolib

from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import suite

ROOT = pathlib.Path(__file__).resolve().parents[2]
STREETS = ROOT / "scenarios" / "streets"
SCENARIOS = sorted(STREETS.glob("*.toml"))
CITIES = ROOT.parent / "shared" / "cities"
_spec = importlib.util.spec_from_file_location("streets_build", STREETS / "build.py")
build = sys.modules[_spec.name] = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(build)


def _net(name: str):
    return sumolib.net.readNet(str(STREETS / f"{name}.net.xml"), withInternal=True, withPedestrianConnections=True)


@pytest.mark.sumo  # runs SUMO's netconvert
def test_build_check_rebuilds_every_net_byte_identically():
    r = subprocess.run([sys.executable, str(STREETS / "build.py"), "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.strip() == f"{len(build.names())} nets rebuilt byte-identically"
    assert len(build.names()) == 5


@pytest.mark.sumo  # runs SUMO's netconvert
def test_check_names_a_net_that_differs(tmp_path, monkeypatch):
    (tmp_path / "zebra.net.xml").write_bytes((STREETS / "zebra.net.xml").read_bytes().replace(b'"13.89"', b'"13.90"', 1))
    monkeypatch.setattr(build, "HERE", tmp_path)
    assert build.check(["zebra"]) == ["zebra"]


def _lanes(net, edge_id: str) -> list[str]:
    """Each lane's kind, right to left: sidewalk, bike, bus or car (passenger cars allowed)."""
    kinds = []
    for lane in net.getEdge(edge_id).getLanes():
        if lane.allows("passenger"):
            kinds.append("car")
        elif lane.allows("pedestrian"):
            kinds.append("sidewalk")
        elif lane.allows("bicycle"):
            kinds.append("bike")
        elif lane.allows("bus"):
            kinds.append("bus")
    return kinds


def test_the_nets_have_the_promised_lanes_and_crossings():
    zebra = _net("zebra")
    assert _lanes(zebra, "W2Z") == ["sidewalk", "car"]
    zc = [e for e in zebra.getEdges() if e.getFunction() == "crossing"]
    assert len(zc) == 1 and zebra.getEdge("W2Z").getToNode().getType() == "priority"
    assert "W2Z" in [c.getFrom().getID() for c in zebra.getEdge("W2Z").getToNode().getConnections()]
    assert _lanes(_net("bike_right_turn"), "W2J") == ["sidewalk", "bike", "car"]
    assert _lanes(_net("van_bike_lane"), "W2E") == ["sidewalk", "bike", "car"]
    assert _lanes(_net("van_bike_lane"), "E2W") == ["sidewalk", "bike", "car"]
    assert _lanes(_net("bus_lane"), "W2J") == ["sidewalk", "bus", "car"]
    cross = _net("signal_crossing")
    assert cross.getNode("C").getType() == "traffic_light"
    assert sorted(e.getID() for e in cross.getEdges() if e.getFunction() == "crossing") == [f":C_c{i}" for i in range(4)]
    assert _lanes(cross, "S2C") == ["sidewalk", "car", "car"]


def test_zebra_crossing_gives_pedestrians_priority():
    """The crossing's link is major ('M'): cars on the street yield to people on it (SUMO's junction logic)."""
    root = ET.parse(STREETS / "zebra.net.xml").getroot()
    states = {(c.get("from"), c.get("to")): c.get("state") for c in root.iter("connection")}
    assert states[(":Z_w1", ":Z_c0")] == "M"
    assert states[("W2Z", "Z2E")] == "m"


@pytest.mark.parametrize("path", SCENARIOS, ids=[p.stem for p in SCENARIOS])
def test_each_scenario_loads(path):
    scn = scenario.load(path)
    assert scn.spec.ego.ids == ("ego",) and scn.spec.ego.controller == "apf_sa" and scn.spec.sim.step_s == 0.1


def test_every_scenario_is_in_the_suite():
    entries = suite.load(ROOT / "scenarios" / "streets.toml")
    suite.check_criteria(entries, "streets.toml")
    assert sorted(e.scenario.resolve() for e in entries) == sorted(p.resolve() for p in SCENARIOS)


def test_district_files_are_read_from_shared_beside_the_repository():
    """A district scenario names files in ../shared/cities/ (beside the repository, as in CI), none copied here."""
    districts = [p for p in SCENARIOS if p.stem.startswith(("bologna_", "berlin_"))]
    assert len(districts) == 6
    for path in districts:
        sim = scenario.read_toml(path)["sim"]
        shared = [f for f in [sim["net"], *sim["routes"], *sim["additional"]] if "shared/cities" in f]
        assert len(shared) >= 4
        for f in shared:
            assert f.startswith("../../../shared/cities/")
            assert (path.parent / f).resolve().is_relative_to(CITIES.resolve()) and (path.parent / f).is_file()
    assert not list(STREETS.glob("*.net.xml.gz")) and not (STREETS / "acosta_peds.net.xml").exists()


DISTRICT_NETS = {"bologna": CITIES / "bologna_acosta" / "acosta_peds.net.xml",
                 "berlin": CITIES / "berlin_doerpfeldstr" / "net.net.xml.gz"}


@pytest.mark.parametrize("city", sorted(DISTRICT_NETS))
def test_district_ego_routes_are_connected_for_a_car_through_four_junctions(city):
    net = sumolib.net.readNet(str(DISTRICT_NETS[city]))
    files = sorted(STREETS.glob(f"{city}_*.rou.xml"))
    assert len(files) == 3
    for f in files:
        ego, = [v for v in ET.parse(f).getroot().iter("vehicle") if v.get("id") == "ego"]
        assert ET.parse(f).getroot().find(f"vType[@id='{ego.get('type')}']").get("vClass") == "passenger"
        edges = [net.getEdge(e) for e in ego.find("route").get("edges").split()]
        for a, b in zip(edges, edges[1:]):
            lanes = [c for c in a.getOutgoing().get(b, []) if c.getFromLane().allows("passenger")
                     and c.getToLane().allows("passenger")]
            assert lanes, f"{f.name}: no car connection {a.getID()} -> {b.getID()}"
        junctions = {e.getToNode().getID() for e in edges[:-1]}
        assert len(junctions) >= 4, f.name


DISTRICT_SCENARIOS = [p for p in SCENARIOS if p.stem.startswith(("bologna_", "berlin_"))]


@pytest.mark.sumo  # runs SUMO on the district
@pytest.mark.parametrize("path", DISTRICT_SCENARIOS, ids=[p.stem for p in DISTRICT_SCENARIOS])
def test_district_ego_departs_and_arrives_in_plain_sumo(path, tmp_path):
    """SUMO itself, with the scenario's files (1 s steps) and driving the ego, gets it from its first edge to its
    last, and writes nothing into the shared district folder."""
    scn = scenario.load(path)
    base = path.parent
    ego_file = base / scn.spec.sim.routes[-1]
    depart = float(next(v for v in ET.parse(ego_file).getroot().iter("vehicle") if v.get("id") == "ego").get("depart"))
    begin = 50300 if path.stem.startswith("berlin_") else 0
    folder = sorted(p.name for p in (base / scn.spec.sim.net).parent.iterdir())
    r = subprocess.run([str(build.netbuild.BIN / "sumo"), "-n", str(base / scn.spec.sim.net),
                        "-r", ",".join(str(base / f) for f in scn.spec.sim.routes),
                        "-a", ",".join(str(base / f) for f in scn.spec.sim.additional),
                        "--begin", str(begin), "--end", str(depart + 600), "--no-step-log", "true",
                        "--no-warnings", "true", "--tripinfo-output", str(tmp_path / "trips.xml")],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    ego, = [t for t in ET.parse(tmp_path / "trips.xml").getroot().iter("tripinfo") if t.get("id") == "ego"]
    edges = next(v for v in ET.parse(ego_file).getroot().iter("vehicle") if v.get("id") == "ego").find("route").get("edges")
    assert float(ego.get("depart")) < depart + 60 and ego.get("arrivalLane").rsplit("_", 1)[0] == edges.split()[-1]
    assert sorted(p.name for p in (base / scn.spec.sim.net).parent.iterdir()) == folder
