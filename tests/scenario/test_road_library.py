"""The road scenario library (scenarios/roads/): the committed nets are what their sources build, the nets
have what the scenarios promise (bends of 30-60 m, roundabouts, light programs, an acceleration lane, an
exit), every scenario is in the suite, and each runs in real SUMO with its egos driving."""
import importlib.util
import math
import pathlib
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import sumolib

from sumo_avoid.runs import outputs
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import suite

ROOT = pathlib.Path(__file__).resolve().parents[2]
ROADS = ROOT / "scenarios" / "roads"
SCENARIOS = sorted(ROADS.glob("*.toml"))
_spec = importlib.util.spec_from_file_location("roads_build", ROADS / "build.py")
build = sys.modules[_spec.name] = importlib.util.module_from_spec(_spec)  # registered: its dataclasses need it
_spec.loader.exec_module(build)


def _net(name: str):
    return sumolib.net.readNet(str(ROADS / f"{name}.net.xml"), withPrograms=True)


def _bend_radii(shape, min_turn_rad: float = 1e-3) -> list[float]:
    """Radius of each bend of a polyline: its length over its heading change, a bend being a run of vertices
    turning the same way (the chords between the first and the last of them; an arc of radius R drawn as m
    chords of angle d turns by d between chords and d/2 where it meets the straights: m R d / (m d) = R)."""
    p = np.asarray(shape, dtype=float)
    seg = np.diff(p, axis=0)
    length = np.hypot(seg[:, 0], seg[:, 1])
    h = np.arctan2(seg[:, 1], seg[:, 0])
    turn = (np.diff(h) + np.pi) % (2 * np.pi) - np.pi  # turn[k] at vertex k + 1, between segments k and k + 1
    sign = np.where(np.abs(turn) > min_turn_rad, np.sign(turn), 0)
    radii, k = [], 0
    while k < len(turn):
        if sign[k] == 0:
            k += 1
            continue
        j = k
        while j + 1 < len(turn) and sign[j + 1] == sign[k]:
            j += 1
        arc = length[k + 1:j + 1].sum()
        radii.append(float(arc / abs(turn[k:j + 1].sum())))
        k = j + 1
    return radii


@pytest.mark.sumo  # runs SUMO's netconvert and netgenerate
def test_committed_nets_are_what_the_sources_build(tmp_path):
    names = build.names()
    assert len(names) == 7
    for name in names:
        out = build.build(name, tmp_path)
        assert out.read_bytes() == (ROADS / out.name).read_bytes(), f"{out.name}: run python scenarios/roads/build.py"


def test_the_nets_have_what_the_scenarios_promise():
    curve = _net("curve")
    # centre-line bends R 40 (left), 55 (right), 35 (left) m; each lane's centre 1.75 m to its right
    for lane, radii in (("W2E_0", [41.75, 53.25, 36.75]), ("E2W_0", [33.25, 56.75, 38.25])):
        assert _bend_radii(curve.getLane(lane).getShape()) == pytest.approx(radii, abs=0.5), lane
    for name, lanes in (("roundabout1", 1), ("roundabout2", 2)):
        net = _net(name)
        (ring,) = net.getRoundabouts()
        assert sorted(ring.getNodes()) == ["E", "N", "S", "W"]
        assert {net.getEdge(e).getLaneNumber() for e in ring.getEdges()} == {lanes}
    for name, kind in (("grid_static", "static"), ("grid_actuated", "actuated")):
        tls = _net(name).getTrafficLights()
        assert len(tls) == 12 and {p.getType() for t in tls for p in t.getPrograms().values()} == {kind}
    ramp = _net("ramp")
    assert ramp.getEdge("m2").getLaneNumber() == 4 and ramp.getEdge("m3").getLaneNumber() == 3
    assert [c.getToLane().getID() for c in ramp.getEdge("ramp").getOutgoing()[ramp.getEdge("m2")]] == ["m2_0"]
    assert ramp.getNode("J2").getType() == "zipper"
    mw = _net("motorway_exit")
    assert sorted(e.getID() for e in mw.getEdge("m1").getOutgoing()) == ["exit", "m2"]
    assert _bend_radii(mw.getLane("m1_1").getShape()) == pytest.approx([405.25], abs=1.0)  # R 400 + 5.25 m


def test_every_library_scenario_is_in_the_suite():
    entries = suite.load(ROOT / "scenarios" / "roads.toml")
    listed = {e.scenario.resolve() for e in entries}
    assert {p.resolve() for p in SCENARIOS} <= listed
    assert {e.scenario.name for e in entries} >= {"overtaking.toml", "left_turn.toml", "local_minimum.toml"}


def _last_ego_depart_s(scn) -> float:
    ids = scn.spec.ego.ids
    departs = [float(v.get("depart")) for f in scn.route_files
               for v in ET.parse(f).getroot().iter("vehicle") if v.get("id") in ids]
    assert len(departs) == len(ids)
    return max(departs)


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.stem)
def test_library_scenario_runs_with_its_egos_driving(path):
    """Each scenario until 3 s after its last ego departs (the full runs are the study: reports/roads/)."""
    scn = scenario.load(path)
    until = _last_ego_depart_s(scn) + 3.0
    res = runner.run(scenario.load(path, [f"sim.duration_s={until}", "output.plots=false"]))
    m = outputs.run_metrics(res)
    egos = res.traj[res.traj["is_ego"].astype(bool)]
    assert set(egos["id"]) == set(scn.spec.ego.ids)
    assert m["path_length_m"] >= 3.0 * 3.0, "the egos did not drive"  # >= 3 m/s on average over 3 s
    assert m["phi_wall"] <= 0.1 and m["wrong_way_m"] == 0.0
    assert math.isfinite(m["min_gap_m"])
