"""Input files SUMO loads are accepted by the scenario loader as well: additional files with the older root
element <add> (the Bologna district's signal programs and bus stops) and gzip-compressed networks (Berlin's
net.net.xml.gz), trip and flow edge ids with spaces around them (Wildau's counted flows, which SUMO trims); a root
SUMO does not know is still refused, naming the file and the key."""
import gzip
import shutil

import pytest
from conftest import ROOT, SCENARIOS

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.scenario import spec as scenario

GOOD = (SCENARIOS / "overtaking.toml").read_text()
NET = ROOT / "nets" / "overtaking.net.xml"


def _scenario(tmp_path, net: str, additional: str, goal: str = "") -> object:
    shutil.copy(SCENARIOS / "overtaking.rou.xml", tmp_path / "overtaking.rou.xml")
    text = GOOD.replace('net = "../nets/overtaking.net.xml"', f'net = "{net}"\nadditional = ["{additional}"]')
    if goal:
        text = text.replace("[ego]", f'[ego]\ngoal = "{goal}"')
    (tmp_path / "s.toml").write_text(text)
    return tmp_path / "s.toml"


POLY = '<poly id="p" type="building" color="1,0,0" fill="1" shape="10,10 20,10 20,20 10,20"/>'


def test_an_additional_file_with_root_add_loads(tmp_path):
    (tmp_path / "old.add.xml").write_text(f"<add>\n    {POLY}\n</add>\n")
    scn = scenario.load(_scenario(tmp_path, str(NET), "old.add.xml"))
    assert scn.spec.sim.additional == ("old.add.xml",)


def test_an_unknown_root_is_refused_naming_file_key_and_the_roots_sumo_loads(tmp_path):
    (tmp_path / "odd.add.xml").write_text(f"<stuff>\n    {POLY}\n</stuff>\n")
    with pytest.raises(ScenarioError) as e:
        scenario.load(_scenario(tmp_path, str(NET), "odd.add.xml"))
    assert "key 'sim.additional[0]'" in str(e.value)
    assert "its root element is <stuff>, expected <routes> or <additional> or <add>" in str(e.value)


def test_a_gzip_network_loads_with_an_edge_goal(tmp_path):
    with open(NET, "rb") as src, gzip.open(tmp_path / "net.net.xml.gz", "wb") as dst:
        shutil.copyfileobj(src, dst)
    (tmp_path / "a.add.xml").write_text(f"<additional>\n    {POLY}\n</additional>\n")
    scn = scenario.load(_scenario(tmp_path, "net.net.xml.gz", "a.add.xml", goal="road"))
    assert scn.spec.sim.net == "net.net.xml.gz" and scn.spec.ego.goal == "road"


def test_a_broken_gzip_network_is_refused_naming_the_key(tmp_path):
    (tmp_path / "net.net.xml.gz").write_bytes(gzip.compress(NET.read_bytes())[:200])
    (tmp_path / "a.add.xml").write_text(f"<additional>\n    {POLY}\n</additional>\n")
    with pytest.raises(ScenarioError) as e:
        scenario.load(_scenario(tmp_path, "net.net.xml.gz", "a.add.xml"))
    assert "key 'sim.net'" in str(e.value)


def test_flow_edges_with_spaces_around_them_load_as_sumo_trims_them(tmp_path):
    """Wildau's flows_SUMOV2.2.rou.xml has to="-111677669#0 " and from="880140407 ": SUMO loads them."""
    flows = ('<routes>\n    <flow id="f" begin="0" end="10" number="2" from=" road" to="road " via=" road "/>\n'
             '</routes>\n')
    (tmp_path / "flows.rou.xml").write_text(flows)
    (tmp_path / "a.add.xml").write_text(f"<additional>\n    {POLY}\n</additional>\n")
    path = _scenario(tmp_path, str(NET), "a.add.xml")
    path.write_text(path.read_text().replace('routes = ["overtaking.rou.xml"]',
                                             'routes = ["overtaking.rou.xml", "flows.rou.xml"]'))
    assert scenario.load(path).spec.sim.routes == ("overtaking.rou.xml", "flows.rou.xml")
    (tmp_path / "flows.rou.xml").write_text(flows.replace('to="road "', 'to="nowhere "'))
    with pytest.raises(ScenarioError) as e:
        scenario.load(path)
    assert "its to edge 'nowhere ' is not in the network" in str(e.value)
