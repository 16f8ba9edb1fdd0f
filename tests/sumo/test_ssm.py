"""SUMO's SSM device on the egos only (sumo_avoid.sumo.ssm_device): its options, its XML read back, and
real runs in which an ego closes on a slower leader."""
import json
import math
import tempfile
import textwrap
import xml.etree.ElementTree as ET

import pandas as pd
import pytest
from conftest import ROOT, run_scenario

from sumo_avoid.metrics.ssm import ssm_summary
from sumo_avoid.runs.outputs import run_metrics
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import ledger
from sumo_avoid.studies.suite import Criterion
from sumo_avoid.sumo.sim import SumoSim, SumoStartError, sumo_args
from sumo_avoid.sumo.ssm_device import (
    COLUMNS,
    SsmParams,
    SsmRequest,
    equip,
    read_conflicts,
    ssm_args,
)

XML = """<?xml version="1.0" encoding="UTF-8"?>
<SSMLog>
    <conflict begin="4.10" end="9.00" ego="ego2" foe="car">
        <minTTC time="6.00" position="75.50,-8.75" type="2" value="1.25" speed="8.00"/>
        <maxDRAC time="5.90" position="75.00,-8.75" type="2" value="3.40" speed="8.00"/>
        <PET time="NA" position="NA" type="NA" value="NA" speed="NA"/>
    </conflict>
    <conflict begin="1.00" end="3.00" ego="ego1" foe="bus">
        <minTTC time="NA" position="NA" type="NA" value="NA" speed="NA"/>
        <maxDRAC time="2.00" position="1.00,2.00" type="9" value="0.80" speed="5.00"/>
        <PET time="2.50" position="3.00,4.00" type="9" value="0.70" speed="5.00"/>
    </conflict>
</SSMLog>
"""


def test_options_and_equipped_copies_of_the_files_defining_egos(tmp_path):
    f = tmp_path / "run" / "ssm.xml"
    f.parent.mkdir()
    args = ssm_args(SsmRequest(("b", "a"), f))
    opt = dict(zip(args[::2], args[1::2]))
    assert opt["--device.ssm.measures"] == "TTC DRAC PET"
    assert opt["--device.ssm.thresholds"] == "5.0 1.0 3.0"
    assert opt["--device.ssm.file"] == str(f) and opt["--device.ssm.trajectories"] == "false"
    assert "--device.ssm.probability" not in opt and "--device.ssm.explicit" not in opt  # see equip()
    assert ssm_args(SsmRequest((), f)) == []
    assert not f.exists()  # building a command line writes no output
    (tmp_path / "egos.rou.xml").write_text(
        '<routes><vType id="car"/><route id="r" edges="road"/>'
        '<vehicle id="ego" type="car" route="r" depart="0"><stop lane="road_1" endPos="80" duration="5"/></vehicle>'
        '<vehicle id="other" type="car" route="r" depart="1"/><trip id="b" from="road" to="road" depart="2"/>'
        '</routes>')
    (tmp_path / "others.rou.xml").write_text('<routes><vehicle id="x" route="r" depart="0"/></routes>')
    (tmp_path / "broken.rou.xml").write_text("<routes><vehicle")
    files = [tmp_path / n for n in ("others.rou.xml", "egos.rou.xml", "broken.rou.xml")]
    req = SsmRequest(("ego", "b"), f)
    out = equip(files, req, "r")
    assert out[0] == files[0] and out[2] == files[2]  # nothing to equip / SUMO reports the XML error
    assert out[1] == f.parent / "r1_egos.rou.xml"
    root = ET.parse(out[1]).getroot()
    params = {e.get("id"): [(p.get("key"), p.get("value")) for p in e.findall("param")] for e in root
              if e.tag in ("vehicle", "trip")}
    assert params == {"ego": [("has.ssm.device", "true")], "other": [], "b": [("has.ssm.device", "true")]}
    assert [c.tag for c in root.find("vehicle")] == ["stop", "param"]  # the rest as it was
    assert [p.name for p in f.parent.iterdir()] == ["r1_egos.rou.xml"]


def test_conflicts_read_back_sorted_with_na_as_missing(tmp_path):
    f = tmp_path / "ssm.xml"
    f.write_text(XML)
    df = read_conflicts(f)
    assert list(df.columns) == COLUMNS
    assert df["ego"].tolist() == ["ego1", "ego2"]  # by begin time
    r = df.iloc[1]
    assert (r.foe, r.begin_s, r.end_s, r.ttc_s, r.ttc_time_s, r.ttc_x, r.ttc_y, r.ttc_type) == (
        "car", 4.1, 9.0, 1.25, 6.0, 75.5, -8.75, 2)
    assert r.drac_mps2 == 3.4 and math.isnan(r.pet_s) and pd.isna(r.pet_type)
    assert math.isnan(df.iloc[0].ttc_s) and df.iloc[0].pet_s == 0.7
    # the run's extremes, clamped at the thresholds (5 s, 1 m/s^2, 3 s)
    assert ssm_summary(df, SsmParams()) == {"min_ttc_s": 1.25, "max_drac_mps2": 3.4, "min_pet_s": 0.7,
                                            "ssm_conflicts": 2}
    none = read_conflicts(tmp_path / "missing.xml")
    assert list(none.columns) == COLUMNS and none.empty
    assert ssm_summary(none, SsmParams()) == {"min_ttc_s": 5.0, "max_drac_mps2": 1.0, "min_pet_s": 3.0,
                                              "ssm_conflicts": 0}
    assert set(ssm_summary(none, None).values()) == {None}  # the device did not run (arena)


def test_sumo_refusing_bad_input_leaves_no_ssm_file(tmp_path):
    bad = tmp_path / "bad.rou.xml"
    bad.write_text("<routes><vehicle id='ego' route='nowhere' depart='0'/></routes>")
    f = tmp_path / "ssm.xml"
    args = sumo_args(ROOT / "nets" / "overtaking.net.xml", [bad], [], 0.1, 1, 0.8, None, ssm=SsmRequest(("ego",), f))
    with pytest.raises(SumoStartError):
        SumoSim(args)
    assert not f.exists()


def _closing(tmp_path, duration_s: float, ego: str = "ego"):
    """The scripted ego at 15 m/s, blind, behind a leader at 5 m/s in its lane (fronts at 20 and 100 m)."""
    (tmp_path / "closing.rou.xml").write_text(textwrap.dedent(f"""\
        <routes>
            <vType id="car" vClass="passenger" length="4.5" width="1.8" sigma="0"/>
            <vType id="slow" vClass="passenger" length="4.5" width="1.8" sigma="0" maxSpeed="5"/>
            <route id="straight" edges="road"/>
            <vehicle id="{ego}" type="car" route="straight" depart="0" departLane="1" departPos="20" departSpeed="15"/>
            <vehicle id="leader" type="slow" route="straight" depart="0" departLane="1" departPos="100" departSpeed="5"/>
        </routes>
        """))
    (tmp_path / "closing.toml").write_text(textwrap.dedent(f"""\
        name = "closing"
        [sim]
        net = "{ROOT / 'nets' / 'overtaking.net.xml'}"
        routes = ["closing.rou.xml"]
        duration_s = {duration_s}
        [ego]
        ids = ["{ego}"]
        controller = "scripted"
        goal = [1400.0, -8.75]
        layers = []
        [controllers.scripted]
        speed_mps = 15.0
        """))
    scn = scenario.load(tmp_path / "closing.toml", [])
    res = runner.run(scn)
    return res, run_metrics(res)


def test_ssm_sees_an_ego_closing_on_a_slower_leader(tmp_path):
    # after 5 s the bumper gap is 75.5 - 10 x 5 = 25.5 m, closing at 10 m/s: TTC 2.55 s (smallest then)
    res, m = _closing(tmp_path, 5.0)
    conflicts = res.tables["ssm_conflicts"]
    # the leader carries no device: with one it would log the same encounter as ego="leader", foe="ego"
    # (seen with --device.ssm.explicit ego,leader)
    assert set(conflicts["ego"]) == {"ego"}
    assert set(conflicts["foe"]) == {"leader"}
    assert m["collisions"] == 0
    assert m["min_ttc_s"] == pytest.approx(2.55, abs=0.15)
    # the plug-in's own 2-D TTC sees the same rear-end approach
    assert m["min_ttc2d_s"] == pytest.approx(m["min_ttc_s"], abs=0.15)
    assert m["ssm_conflicts"] == 1 and m["max_drac_mps2"] > 1.0
    # scalars: ledger columns (and so usable in suite criteria)
    cols = ledger.scalar_metrics(m)
    for k in ("min_ttc_s", "max_drac_mps2", "min_pet_s", "ssm_conflicts", "min_ttc2d_s", "wrong_way_m",
              "off_road_m", "max_abs_jerk_mps3", "max_lat_accel_mps2"):
        assert k in cols and cols[k] is not None
    rows = [{"seed": 1, **cols}]
    assert Criterion.parse("min_ttc_s >= 2").check(rows)[0] and not Criterion.parse("min_ttc_s >= 3").check(rows)[0]
    assert Criterion.parse("wrong_way_m == 0").check(rows)[0] and Criterion.parse("off_road_m_max <= 0").check(rows)[0]


def test_every_run_in_one_process_equips_its_own_egos(tmp_path):
    # with --device.ssm.explicit SUMO kept the first list of the process (here "ego", from the
    # tests above, or "car_a"): "car_b" would carry no device and log nothing
    for name in ("car_a", "car_b"):
        (tmp_path / name).mkdir()
        res, m = _closing(tmp_path / name, 5.0, ego=name)
        assert set(res.tables["ssm_conflicts"]["ego"]) == {name} and m["min_ttc_s"] < 3.0


def test_a_collision_is_ttc_zero_repeats_and_leaves_no_file(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # where the run's SSM file goes
    res, m = run_scenario("crash_straight")
    assert m["collisions"] == 1 and m["min_ttc_s"] == 0.0 and m["min_ttc2d_s"] == 0.0
    assert res.tables["ssm_conflicts"]["ttc_type"].tolist() == [111]  # SUMO's code for a collision
    assert list(tmp_path.iterdir()) == []  # the temporary folder is gone
    _, again = run_scenario("crash_straight")
    assert json.dumps(again, sort_keys=True) == json.dumps(m, sort_keys=True)
