"""Three cases of the bad-input corpus that crashed (issue 35), checked like every case
(:func:`corpus.check`: exit code 2, one stderr line naming the file and the key, no traceback, nothing
written): absurd finite magnitudes in an arena (``size_m = 1e300`` overflowed numpy mid-run, exit 3);
well-formed files of the right kind that SUMO refuses once it starts (it said only "Process Error":
now the file and SUMO's own first error line); a ledger whose ``runs`` table lacks columns (a pandas
traceback in ``report``)."""
from __future__ import annotations

import sqlite3

import pytest
from conftest import cli_in_process
from corpus import ROUTES, Call, Case, base, check, scenario

POLY = '<additional><poly id="p" shape="x y z"/></additional>'
VTYPE = '<routes><vType id="t" accel="fast"/></routes>'


def _sumo_refuses(key: str, name: str, text: str, reason: str) -> Case:
    """``name`` holding ``text``, as an additional or a second route file: the line names it and SUMO's ``reason``."""
    sim = f'additional = ["{{tmp}}/{name}"]' if key.startswith("sim.additional") else ""
    routes = (ROUTES, f"{{tmp}}/{name}") if key.startswith("sim.routes") else (ROUTES,)
    case = scenario(base(sim=sim, routes=routes), key, files={name: text}, sub=True)

    def make(tmp):
        call = case.make(tmp)
        return Call(call.argv, (*call.names, f"a file SUMO can load: {tmp / name} (SUMO: {reason}"), call.cwd)
    return Case(case.family, make, case.sub)


def _ledger_without(tmp, columns: str) -> Call:
    led = tmp / "old.sqlite"
    with sqlite3.connect(led) as con:
        con.execute(f"CREATE TABLE runs ({columns})")
        con.execute("INSERT INTO runs (key, status) VALUES ('k1', 'done')")
    con.close()
    return Call(["report", led, "--out", tmp / "r.html"], (f"{led}: key 'runs'",), cwd=tmp)


# (the key the line names, the [arena] table's lines)
ABSURD = (("size_m", "size_m = 1e300"), ("size_m", "size_m = 1e7"), ("origin", "origin = [1e300, 0.0]"),
          ("starts", "n_agents = 1\nstarts = [[0.0, -1e300]]"), ("length_m", "length_m = 1e300"),
          ("initial_speed_mps", "initial_speed_mps = 1e300"))
CASES = {
    **{f"arena_{i}_{key}": scenario(base(f"[arena]\n{lines}"), f"arena.{key}") for i, (key, lines) in enumerate(ABSURD)},
    "additional_sumo_refuses": _sumo_refuses("sim.additional[0]", "a.add.xml", POLY,
                                             "Attribute 'shape' in definition of poly 'p' is not a valid list of "
                                             "positions."),
    "routes_sumo_refuses": _sumo_refuses("sim.routes[1]", "r.rou.xml", VTYPE,
                                         "Invalid Car-Following-Model Attribute accel. Cannot be parsed to float"),
    "report_ledger_missing_columns": Case("report", lambda t: _ledger_without(t, "key TEXT PRIMARY KEY, status TEXT")),
}


@pytest.mark.parametrize("name", [pytest.param(n, marks=[pytest.mark.sumo] if c.sub else []) for n, c in CASES.items()])
def test_bad_input(name, tmp_path):
    check(CASES[name], tmp_path)


def test_the_missing_columns_are_named(tmp_path):
    call = _ledger_without(tmp_path, "key TEXT PRIMARY KEY, status TEXT, scenario TEXT, error TEXT")
    r = cli_in_process(*call.argv, cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.strip().endswith("(missing: controller, seed)"), r.stderr
