"""A controller from another package (docs/plugins.md): the three-file package of that page, built
and installed with pip into a folder of its own (``--target``, then ``PYTHONPATH``: the test venv
stays as it is), found by its entry point and by its import path in ``run``, ``batch`` (2 workers,
each run in its own process) and ``suite``; its table validated like a built-in's; a typo in its
import path one line naming the key, exit code 2."""
import json
import os
import re
import sqlite3
import subprocess
import sys

import pytest
from conftest import ROOT, SCENARIOS, cli_in_process

from sumo_avoid.control import CONTROLLERS

OVERTAKING = SCENARIOS / "overtaking.toml"
PATH = "steadyctl.control:SteadyController"
SHORT = ["--set", "sim.duration_s=8", "--set", "output.plots=false"]


def doc_files() -> dict[str, str]:
    """The package's files, as docs/plugins.md shows them (**`NAME`** then a code block)."""
    text = (ROOT / "docs" / "plugins.md").read_text()
    return dict(re.findall(r"\*\*`([^`]+)`\*\*\n\n```\w*\n(.*?)```", text, flags=re.S))


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The package of docs/plugins.md, pip-installed into a folder of its own."""
    tmp = tmp_path_factory.mktemp("plugin")
    files = doc_files()
    assert sorted(files) == ["pyproject.toml", "steadyctl/__init__.py", "steadyctl/control.py"]
    for name, text in files.items():
        (tmp / "src" / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp / "src" / name).write_text(text)
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                    "--target", str(tmp / "site"), str(tmp / "src")], check=True, capture_output=True)
    return tmp / "site"


def cli(site, *args, cwd=None):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)}
    return subprocess.run([sys.executable, "-m", "sumo_avoid.cli", *map(str, args)], capture_output=True, text=True,
                          env=env, cwd=cwd or ROOT)


@pytest.fixture
def importable(site, monkeypatch):
    """The package importable in this process (for what the CLI refuses before SUMO starts), forgotten after."""
    monkeypatch.syspath_prepend(str(site))
    yield
    CONTROLLERS._found.clear()
    for name in [m for m in sys.modules if m.split(".")[0] == "steadyctl"]:
        del sys.modules[name]


def test_listed_with_its_origin(importable):
    res = cli_in_process("controllers", PATH)
    assert res.returncode == 0, res.stderr
    rows = {line.split()[0]: line for line in res.stdout.splitlines()}
    assert "entry point (steadyctl)" in rows["steady"] and "Follow the route" in rows["steady"]
    assert "import path" in rows[PATH]
    assert "built-in" in rows["apf_sa"]


def scenario_with(tmp_path, controller: str, table: str) -> object:
    """overtaking.toml in tmp_path (its files by absolute path), driven by ``controller`` at 12 m/s."""
    text = OVERTAKING.read_text().replace('controller = "apf_sa"', f'controller = "{controller}"')
    text = text.replace('"../nets/', f'"{ROOT}/nets/').replace('"overtaking.rou.xml"', f'"{SCENARIOS}/overtaking.rou.xml"')
    path = tmp_path / "scn.toml"
    path.write_text(text + f"\n[controllers.{table}]\nspeed_mps = 12.0\n")
    return path


def test_run_by_entry_point_and_by_import_path(site, tmp_path):
    speeds = {}
    for name, table in (("steady", "steady"), (PATH, f'"{PATH}"')):
        out = tmp_path / f"out-{len(speeds)}"
        res = cli(site, "run", scenario_with(tmp_path, name, table), "--out", out, "--no-plots", "--quiet", *SHORT)
        assert res.returncode == 0, res.stderr
        m = json.loads((out / "metrics.json").read_text())
        assert m["controller"] == name
        speeds[name] = m["mean_speed_mps"]
    # its table reached it: 12 m/s asked, not the default 8 (a little above while it slows down from its depart speed)
    assert all(11.5 < v < 13.5 for v in speeds.values()), speeds
    assert speeds["steady"] == pytest.approx(speeds[PATH])


def test_batch_with_two_workers_and_a_suite(site, tmp_path):
    ledger = tmp_path / "batch" / "ledger.sqlite"
    res = cli(site, "batch", OVERTAKING, "--seeds", "1-2", "--controller", "steady", "--controller", PATH,
              "--workers", "2", "--ledger", ledger, "--quiet", *SHORT)
    assert res.returncode == 0, res.stdout + res.stderr
    with sqlite3.connect(ledger) as db:
        rows = db.execute("SELECT controller, status FROM runs").fetchall()
    assert sorted(rows) == sorted([("steady", "done")] * 2 + [(PATH, "done")] * 2)
    suite = tmp_path / "suite.toml"
    suite.write_text(f'[defaults]\nseeds = "1-2"\nset = ["sim.duration_s=8", "output.plots=false"]\n\n'
                     f'[[entry]]\nname = "steady"\nscenario = "{OVERTAKING}"\ncontroller = "steady"\n'
                     f'criteria = ["path_length_m >= 20", "collisions == 0"]\n\n'
                     f'[[entry]]\nname = "by path"\nscenario = "{OVERTAKING}"\ncontroller = "{PATH}"\n'
                     f'criteria = ["path_length_m >= 20"]\n')
    res = cli(site, "suite", suite, "--workers", "2", "--ledger", tmp_path / "suite" / "ledger.sqlite",
              "--junit", tmp_path / "junit.xml", "--quiet")
    assert res.returncode == 0, res.stdout + res.stderr
    assert 'failures="0"' in (tmp_path / "junit.xml").read_text()


@pytest.mark.parametrize("args, key, says", [
    (["--controller", "steadyctl.contrl:SteadyController"], "ego.controller", "No module named 'steadyctl.contrl'"),
    (["--controller", "steadyctl.control:SteadyControler"], "ego.controller", "has no attribute 'SteadyControler'"),
    (["--controller", "steady", "--set", "controllers.steady.speeed_mps=3"], "controllers.steady.speeed_mps",
     "known keys"),
    (["--controller", "steady", "--set", "controllers.steady.speed_mps=-3"], "controllers.steady.speed_mps",
     "positive"),
])
def test_a_typo_is_one_line_naming_the_key(importable, tmp_path, args, key, says):
    out = tmp_path / "out"
    res = cli_in_process("run", OVERTAKING, "--out", out, *args)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and f"key '{key}'" in lines[0] and says in lines[0], res.stderr
    assert not out.exists()
