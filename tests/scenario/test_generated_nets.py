"""The generated-network suite (scenarios/generated/make.py): a net rebuilt from scratch is byte-identical
to the committed one (net, traffic, ego route, scenario), its ego route passes >= 3 intersections, and the
suite covers >= 20 nets. Real SUMO tools (netgenerate, netconvert, randomTrips.py, duarouter)."""
import importlib.util
import pathlib
import sys
import xml.etree.ElementTree as ET

import pytest
import sumolib

from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import suite

ROOT = pathlib.Path(__file__).resolve().parents[2]
GEN = ROOT / "scenarios" / "generated"
_spec = importlib.util.spec_from_file_location("generated_make", GEN / "make.py")
make = sys.modules[_spec.name] = importlib.util.module_from_spec(_spec)  # registered: its dataclasses need it
_spec.loader.exec_module(make)


def _intersections(net, edge_ids) -> list[str]:
    """Nodes the route passes (not its ends) that join >= 3 other nodes."""
    out = []
    for eid in edge_ids[:-1]:
        node = net.getEdge(eid).getToNode()
        others = {e.getFromNode().getID() for e in node.getIncoming()} | {e.getToNode().getID() for e in node.getOutgoing()}
        if len(others) >= 3:
            out.append(node.getID())
    return out


@pytest.mark.sumo  # runs SUMO's netgenerate, netconvert, randomTrips.py and duarouter
def test_a_generated_net_rebuilds_byte_identical_with_an_ego_route_through_3_junctions(tmp_path):
    name = "spider01"  # the spider net whose inner circle becomes a roundabout (netgenerate + netconvert pass)
    make.build_one(name, tmp_path)
    built = sorted(p.name for p in (tmp_path / name).iterdir())
    assert built == sorted(p.name for p in (GEN / name).iterdir())
    assert set(built) == {"bg.rou.xml", "ego.rou.xml", f"{name}.net.xml", "scenario.toml"}
    for f in built:
        assert (tmp_path / name / f).read_bytes() == (GEN / name / f).read_bytes(), f
    net = sumolib.net.readNet(str(tmp_path / name / f"{name}.net.xml"))
    (route,) = ET.parse(tmp_path / name / "ego.rou.xml").getroot().iter("route")
    edges = route.get("edges").split()
    assert len(_intersections(net, edges)) >= 3
    (ring,) = net.getRoundabouts()
    assert set(_intersections(net, edges)) & set(ring.getNodes()), "the ego route misses the roundabout"
    assert sum(1 for _ in ET.parse(tmp_path / name / "bg.rou.xml").getroot().iter("vehicle")) >= 10
    scn = scenario.load(tmp_path / name / "scenario.toml")
    assert scn.spec.ego.ids == ("ego",) and scn.spec.ego.controller == "apf_sa"


def test_the_generated_suite_covers_20_nets_of_every_kind():
    entries = suite.load(ROOT / "scenarios" / "generated.toml")
    nets = {e.scenario.parent.name for e in entries}
    assert len(entries) == len(nets) >= 20 and nets == set(make.NETS)
    assert all(e.scenario.exists() and e.controller == "apf_sa" for e in entries)
    assert {n.rstrip("0123456789") for n in nets} == {"grid", "spider", "rand"}
    assert suite.load(ROOT / "scenarios" / "generated.toml")[0].seeds == (1, 2, 3, 4, 5)
