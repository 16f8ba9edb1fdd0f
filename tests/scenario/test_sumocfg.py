"""SUMO configurations as scenarios (sumo_avoid/scenario/sumocfg.py): the Bologna district's own
run.sumocfg, untouched, run with ``--ego`` gives the metrics.json of the same scenario written as
TOML (and of a TOML naming it in ``sim.sumocfg``); the configuration's options reach SUMO, those the
plug-in owns are left out with a note in sumo.log; TOML keys override; begin/end; bad
configurations are one line naming the file and the option, exit 2, nothing written."""
import json
import pathlib
import shutil
import subprocess
import sys

import libsumo
import pytest
from conftest import DATA, ROOT, SCENARIOS, cli_in_process

from sumo_avoid.runs import outputs, runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.sumo.sim import sumo_args

BOLOGNA = ROOT.parent / "shared" / "cities" / "bologna_acosta" / "run.sumocfg"
EGO = "Audinot_7_0"  # departs at t=0, a route of three edges (131 117 209)
needs_bologna = pytest.mark.skipif(not BOLOGNA.is_file(), reason="../shared/cities/bologna_acosta is not beside the checkout")


def metrics_text(scn) -> str:
    """metrics.json of a run of ``scn`` in this process, as the run writes it."""
    return json.dumps(outputs.run_metrics(runner.run(scn)), indent=2, sort_keys=True) + "\n"


@needs_bologna
def test_bologna_run_sumocfg_gives_the_metrics_of_its_toml(tmp_path):
    out = tmp_path / "out"
    res = subprocess.run([sys.executable, "-m", "sumo_avoid.cli", "run", str(BOLOGNA), "--ego", EGO,
                          "--set", "sim.duration_s=40", "--out", str(out), "--no-plots", "--quiet"],
                         capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    got = (out / "metrics.json").read_text()
    assert json.loads(got)["scenario"] == "run" and json.loads(got)["per_ego"][EGO]["path_length_m"] > 100
    log = (out / "sumo.log").read_text()
    for opt in ("tripinfo-output", "stop-output", "log", "gui-settings-file"):
        assert f"sumo-avoid: option '{opt}' of run.sumocfg not used: " in log
    assert not (BOLOGNA.parent / "tripinfos.xml").exists() and not (tmp_path / "tripinfos.xml").exists()
    assert metrics_text(scenario.load(DATA / "sumocfg" / "bologna_run.toml")) == got
    assert metrics_text(scenario.load(DATA / "sumocfg" / "bologna_via_sumocfg.toml")) == got


@needs_bologna
def test_bologna_configuration_read_as_sumo_reads_it():
    scn = scenario.load(BOLOGNA, [f"ego.ids=[\"{EGO}\"]"])
    twin = scenario.load(DATA / "sumocfg" / "bologna_run.toml", ["sim.duration_s=120"])
    assert (scn.net_file, scn.route_files, scn.additional_files) == (twin.net_file, twin.route_files,
                                                                     twin.additional_files)
    assert [f.name for f in scn.route_files] == ["acosta.rou.xml", "persontrips.rou.xml", "acosta_busses.rou.xml"]
    assert scn.sumo_options == twin.sumo_options == (("pedestrian.striping.reserve-oncoming", "0.34"),)
    assert (scn.spec.sim.step_s, scn.spec.sim.duration_s, scn.spec.sim.begin_s) == (0.1, 120.0, 0.0)  # SUMO sets none
    args = sumo_args(scn.net_file, scn.route_files, scn.additional_files, 0.1, 1, 0.8, None,
                     options=scn.sumo_options)
    assert args[args.index("--pedestrian.striping.reserve-oncoming") + 1] == "0.34"
    assert args[args.index("--collision.action") + 1] == "warn" and "--tripinfo-output" not in args


def overtaking_cfg(tmp_path, body: str, name="city.sumocfg") -> pathlib.Path:
    """A configuration in tmp_path/cfg/ whose files sit in tmp_path/files/ (relative paths)."""
    (tmp_path / "files").mkdir(exist_ok=True)
    shutil.copy(ROOT / "nets" / "overtaking.net.xml", tmp_path / "files")
    rou = (SCENARIOS / "overtaking.rou.xml").read_text().replace('depart="0"', 'depart="2"')
    (tmp_path / "files" / "late.rou.xml").write_text(rou)
    (tmp_path / "files" / "bad.rou.xml").write_text('<routes><vehicle id="ego" depart="2"><route edges="nowhere"/>'
                                                     '</vehicle></routes>\n')
    (tmp_path / "cfg").mkdir(exist_ok=True)
    path = tmp_path / "cfg" / name
    path.write_text(f"<configuration>\n{body}\n</configuration>\n")
    return path


FILES = ('<input><net-file value="../files/overtaking.net.xml"/>'
         '<route-files value="../files/late.rou.xml"/></input>')


class Options:
    """A rollout callback reading SUMO's options as SUMO took them."""

    def __init__(self, *names):
        self.names, self.seen = names, {}

    def on_step(self, snap, n_steps):
        self.seen = self.seen or {n: libsumo.simulation.getOption(n) for n in self.names}

    def on_end(self):
        pass


def test_begin_end_step_and_options_from_the_configuration(tmp_path):
    cfg = overtaking_cfg(tmp_path, FILES + '<time><begin value="2"/><end value="0:00:07"/><step-length value="0.05"/>'
                                          '</time><random_number><seed value="7"/></random_number><processing>'
                                          '<pedestrian.striping.reserve-oncoming value="0.4"/><time-to-teleport '
                                          'value="30"/></processing>')
    scn = scenario.load(cfg, ['ego.ids=["ego"]', "output.plots=false"])
    sim = scn.spec.sim
    assert (sim.begin_s, sim.duration_s, sim.step_s, sim.seed) == (2.0, 5.0, 0.05, 7)
    assert scn.net_file == (tmp_path / "files" / "overtaking.net.xml").resolve()
    seen = Options("pedestrian.striping.reserve-oncoming", "time-to-teleport", "seed", "begin")
    res = runner.run(scn, log_file=tmp_path / "sumo.log", callbacks=[seen])
    assert res.steps == 100 and res.sim_time_s == pytest.approx(7.0)
    assert res.traj["time_s"].min() == pytest.approx(2.05)
    assert seen.seen == {"pedestrian.striping.reserve-oncoming": "0.4", "time-to-teleport": "-1", "seed": "7",
                         "begin": "2.0"}
    assert "option 'time-to-teleport' of city.sumocfg not used: " in (tmp_path / "sumo.log").read_text()


def test_toml_keys_override_the_configuration(tmp_path):
    cfg = overtaking_cfg(tmp_path, FILES + '<time><step-length value="0.2"/><end value="30"/></time>'
                                           '<processing><lateral-resolution value="0.6"/></processing>')
    toml = tmp_path / "cfg" / "scn.toml"
    toml.write_text('name = "x"\n[sim]\nsumocfg = "city.sumocfg"\nstep_s = 0.1\n'
                    '[sim.options]\n"pedestrian.striping.reserve-oncoming" = 0.5\n[ego]\nids = ["ego"]\n')
    sim = scenario.load(toml).spec.sim
    assert (sim.step_s, sim.duration_s, sim.lateral_resolution_m) == (0.1, 30.0, 0.6)
    assert scenario.load(toml).sumo_options == (("pedestrian.striping.reserve-oncoming", "0.5"),)


BAD = {  # configuration body, key named, what the line says
    "unknown_option": (FILES + '<processing><no-such-option value="1"/></processing>', "no-such-option",
                       "an option of SUMO"),
    "bad_time": (FILES + '<time><step-length value="fast"/></time>', "step-length", "a time in s"),
    "bad_bool": (FILES + '<processing><ignore-route-errors value="maybe"/></processing>', "ignore-route-errors",
                 "true or false"),
    "missing_route_file": (FILES.replace("late.rou.xml", "late.rou.xml gone.rou.xml"), "route-files",
                           "existing files"),
    "route_file_sumo_refuses": (FILES.replace("late.rou.xml", "bad.rou.xml"), "route-files",
                                "a file SUMO can load"),
    "lateral_resolution": (FILES + '<processing><lateral-resolution value="-1"/></processing>', "lateral-resolution",
                           "a non-negative number"),
    "end_before_begin": (FILES + '<time><begin value="10"/><end value="5"/></time>', "end", "an end after the begin"),
    "no_net": ('<input><route-files value="../files/late.rou.xml"/></input>', "net-file", "a SUMO network file"),
    "syntax": (FILES + "<time>", "<syntax>", "XML"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_configuration_is_one_line_naming_file_and_option(tmp_path, case):
    body, key, says = BAD[case]
    cfg = overtaking_cfg(tmp_path, body)
    out = tmp_path / "out"
    res = cli_in_process("run", cfg, "--ego", "ego", "--out", out)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"sumo-avoid: error: {cfg}: key '{key}'") and says in lines[0], res.stderr
    assert not out.exists()


@pytest.mark.parametrize("option, key, says", [
    ('"no-such-option" = 1', "sim.options.no-such-option", "an option of SUMO"),
    ('"collision.action" = "teleport"', 'sim.options."collision.action"', "an option the plug-in does not set itself"),
    ('"step-length" = 0.2', "sim.options.step-length", "the key sim.step_s"),
    ('"device.rerouting.probability" = "often"', 'sim.options."device.rerouting.probability"', "a number"),
])
def test_bad_sim_options_name_the_key(tmp_path, option, key, says):
    toml = tmp_path / "scn.toml"
    toml.write_text((SCENARIOS / "overtaking.toml").read_text().replace('"../nets/', f'"{ROOT}/nets/')
                    .replace('"overtaking.rou.xml"', f'"{SCENARIOS}/overtaking.rou.xml"') + f"\n[sim.options]\n{option}\n")
    res = cli_in_process("run", toml, "--out", tmp_path / "out")
    assert res.returncode == 2 and f"key '{key}'" in res.stderr and says in res.stderr, res.stderr


def test_a_configuration_without_egos_asks_for_ego(tmp_path):
    res = cli_in_process("run", overtaking_cfg(tmp_path, FILES), "--out", tmp_path / "out")
    assert res.returncode == 2 and "key '--ego'" in res.stderr and "--ego ID" in res.stderr


def test_an_ego_the_configuration_does_not_define_names_the_flag(tmp_path):
    res = cli_in_process("run", overtaking_cfg(tmp_path, FILES), "--ego", "nobody", "--out", tmp_path / "out")
    assert res.returncode == 2 and "key '--ego'" in res.stderr and "got 'nobody'" in res.stderr, res.stderr
