import contextlib
import dataclasses
import io
import os
import pathlib
import sqlite3

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
DATA = pathlib.Path(__file__).resolve().parent / "data"
# the studies' tests (batch, tune, Dask): a short overtaking run, the ledger columns compared, a tiny gain search
OVERTAKING = SCENARIOS / "overtaking.toml"
SHORT = ["sim.duration_s=5", "output.plots=false"]
METRIC_COLS = ["collisions", "min_gap_m", "phi_coll", "phi_wall", "mean_speed_mps", "path_length_m", "steps",
               "sumo_collisions", "goal_reached"]
GAP = SCENARIOS / "formation" / "gap.toml"
TINY_TUNE = ["--generations", "1", "--nests", "3", "--seeds", "2", "--set", "sim.duration_s=1", "--quiet"]


def netconvert(src: str, out_dir: pathlib.Path, name: str, *options: str) -> pathlib.Path:
    """Build ``out_dir/NAME.net.xml`` with SUMO's netconvert from the plain XML in tests/data/SRC
    (NAME.nod.xml, NAME.edg.xml and, if there, NAME.con.xml, copied beside it); ``--no-turnarounds``."""
    import shutil
    import subprocess

    import sumo

    args = []
    for kind, flag in (("nod", "-n"), ("edg", "-e"), ("con", "-x")):
        f = DATA / src / f"{name}.{kind}.xml"
        if f.exists():
            shutil.copy(f, out_dir / f.name)
            args += [flag, str(out_dir / f.name)]
    net = out_dir / f"{name}.net.xml"
    subprocess.run([str(pathlib.Path(sumo.SUMO_HOME) / "bin" / "netconvert"), *args, "--no-turnarounds", "true",
                    *options, "-o", str(net)], check=True, capture_output=True)
    return net


@pytest.fixture
def scenario_path():
    return lambda name: SCENARIOS / f"{name}.toml"


def run_scenario(name: str, **kw):
    """Run a real scenario in real SUMO (libsumo) and return (RunResult, metrics dict)."""
    from sumo_avoid.runs import outputs as evaluate
    from sumo_avoid.runs import runner
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(SCENARIOS / f"{name}.toml", kw.pop("overrides", []), **kw)
    res = runner.run(scn)
    return res, evaluate.run_metrics(res)


@dataclasses.dataclass
class CliResult:
    returncode: int
    stdout: str
    stderr: str


def cli_in_process(*args, cwd=None) -> CliResult:
    """``sumo-avoid ARGS`` in this process: for input the CLI rejects before SUMO starts (a fresh
    interpreter costs ~2.5 s of imports per call). An exception escaping ``main`` fails the test
    as a traceback would; SUMO's own C++ output is not captured here, so cases that reach SUMO
    run the real command in a subprocess."""
    from sumo_avoid import cli

    out, err = io.StringIO(), io.StringIO()
    old = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = cli.main([str(a) for a in args])
    finally:
        os.chdir(old)
    return CliResult(rc, out.getvalue(), err.getvalue())


_STARTS_SUMO = ("runner.run", "run_scenario", "SumoSim", "main([", "run_batch", "run_suite", "run_one(", "subprocess",
                "sumo_avoid.cli", "radar_study", "benchmarks")


def pytest_collection_modifyitems(items):
    """Mark the tests that start SUMO (``pytest -m "not sumo"`` runs the pure ones in seconds): a test
    whose own source, a module-level helper it calls or a fixture of the test suite it uses (not one
    of pytest's own, e.g. ``tmp_path``) starts a simulation, a batch run or a CLI process.
    Sources are read once per function and helpers listed once per module (a parametrised test
    is one function for all its cases)."""
    import functools
    import inspect

    source = functools.cache(inspect.getsource)

    @functools.cache
    def helpers(module) -> tuple:
        return tuple(h for h in (getattr(module, n, None) for n in list(module.__dict__) if n.startswith("_") or n.islower())
                     if inspect.isfunction(h) and h.__module__ == module.__name__)

    for item in items:
        fn = getattr(item, "function", None)
        if fn is None or item.get_closest_marker("sumo"):
            continue
        src = source(fn)
        called = [source(h) for h in helpers(item.module) if f"{h.__name__}(" in src]
        fixtures = [source(d.func) for name in item.fixturenames  # a fixture of the module or of conftest.py
                    for d in item._fixtureinfo.name2fixturedefs.get(name, ()) if d.baseid]
        if any(k in text for text in [src, *called, *fixtures] for k in _STARTS_SUMO) or "scenario_path" in item.fixturenames:
            item.add_marker("sumo")


def pytest_configure(config):
    """Compile the radar's numba kernel once, here, before the test workers start (pytest-xdist): on a
    machine where it is not cached yet every worker, and every batch's fork server, would otherwise
    compile it at the same time (7-8 s of CPU each on this 2-core machine); later runs load it (~1 s)."""
    if not hasattr(config, "workerinput"):  # the controller (or a run without workers), not a worker
        from sumo_avoid.sensing import occlusion

        occlusion.warm()


def ledger_rows(db: pathlib.Path) -> int:
    """Rows in a ledger a running batch writes (0 while it has no table yet)."""
    if not db.is_file():
        return 0
    with contextlib.closing(sqlite3.connect(db)) as con:
        try:
            return con.execute("SELECT count(*) FROM runs").fetchone()[0]
        except sqlite3.OperationalError:
            return 0


def assert_refused(r: CliResult, key: str, out: pathlib.Path) -> None:
    """Bad input: exit code 2, one line on stderr naming ``key``, nothing written to ``out``."""
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and f"'{key}'" in r.stderr, r.stderr
    assert not out.exists()


def sigkill_at(args, db: pathlib.Path, rows: int) -> None:
    """Start ``sumo-avoid ARGS`` in a fresh process and SIGKILL it once its ledger ``db`` holds ``rows`` runs
    (it must not have finished by then); a second later, so that the runs it started are gone too."""
    import signal
    import subprocess
    import sys
    import time

    proc = subprocess.Popen([sys.executable, "-m", "sumo_avoid.cli", *map(str, args)], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env={**os.environ, "CI": "true"})
    try:
        deadline = time.time() + 120
        while ledger_rows(db) < rows and proc.poll() is None and time.time() < deadline:
            time.sleep(0.02)
        assert proc.poll() is None, "the command finished before it could be killed"
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    finally:
        proc.kill()
    time.sleep(1.0)
