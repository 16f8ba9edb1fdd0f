"""``sumo-avoid tune flocking``: the GA's search space by hand (Table 3's hull widened, log scaling),
the candidates' overrides against the scenario's preset, the warm start (``--start-from scenario``: the
scenario's parameters in the unit cube by hand, one individual of generation 0; ``random`` the search main
made before it), bad input as one line, and on real libsumo a tiny search: each candidate's fitness is the
mean of its runs' μ in the ledger, the population best never falls (elitism), ``--start-from random`` is
the default run file for file, and a search (warm-started or not) killed with SIGKILL mid-generation
resumes to the same files."""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import pandas as pd
import pytest
from conftest import ROOT, SCENARIOS, assert_refused, cli_in_process, ledger_rows, sigkill_at

from sumo_avoid.cli import main
from sumo_avoid.control.flocking.terms import PRESETS
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.studies import ledger
from sumo_avoid.studies.tune_flocking import (PARAMS, Bound, bounds, default_bounds, fitness, fixed_overrides,
                                              overrides, search, values, warm_start)

ARENA4, ARENA6 = SCENARIOS / "arena_v4.toml", SCENARIOS / "arena_v6.toml"
# 5 vehicles starting at v_flock for 3 s: generation 0 and 1 of 4 candidates x 2 seeds, then 2 fresh seeds x
# (best, scenario's)
SETS = ("arena.n_agents=5", "arena.initial_speed_mps=4.0", "sim.duration_s=3")
TINY = ["--generations", "1", "--pop-size", "4", "--seeds", "2", "--evals", "2",
        *(x for s in SETS for x in ("--set", s)), "--quiet"]
TINY_RUNS = 4 * 2 + 4 * 2 + 2 * 2


def test_default_bounds_are_table3s_hull_widened_by_a_quarter():
    b = {x.name: x for x in default_bounds()}
    assert tuple(b) == PARAMS and len(PARAMS) == 11
    # bounds are kept to 6 significant digits (rel 5e-6)
    # linear: hull [17.3, 63.5] (v4 low, v8 high), width 46.2, 5.775 more on each side
    assert (b["r0_rep_m"].lo, b["r0_rep_m"].hi, b["r0_rep_m"].log) == (11.525, 69.275, False)
    assert (b["r0_frict_m"].lo, b["r0_frict_m"].hi) == (pytest.approx(51.3 - 7.8375, rel=1e-5),
                                                        pytest.approx(114 + 7.8375, rel=1e-5))
    assert (b["r0_shill_m"].lo, b["r0_shill_m"].hi) == (0.0, pytest.approx(15.1 * 1.125, rel=1e-5))  # stops at 0
    assert (b["a_shill_mps2"].lo, b["a_shill_mps2"].hi, b["a_shill_mps2"].log) == (
        pytest.approx(1.24 - 1.09375, rel=1e-5), pytest.approx(9.99 + 1.09375, rel=1e-5), False)  # ratio 8.1: linear
    # log: hull [0.03, 0.37] spans 12.3x; an eighth of that ratio's log on each side
    r = 0.37 / 0.03
    assert b["p_rep_ps"].log and b["p_rep_ps"].lo == pytest.approx(0.03 / r ** 0.125, rel=1e-5)
    assert b["p_rep_ps"].hi == pytest.approx(0.37 * r ** 0.125, rel=1e-5)
    # Table 3 prints p_frict's range from 0.0; the model needs p > 0: 0.05 (the printed precision), then log
    assert (b["p_frict_ps"].lo, b["p_frict_ps"].log) == (0.05, True)
    assert b["p_frict_ps"].hi == pytest.approx(10.0 * 200 ** 0.125, rel=1e-5)
    assert {n for n, x in b.items() if x.log} == {"p_rep_ps", "c_frict", "v_frict_mps", "p_frict_ps", "a_frict_mps2",
                                                  "p_shill_ps"}
    for v in (4, 6, 8):  # the paper's own values lie inside
        assert all(b[n].lo <= PRESETS[f"paper_v{v}"][n] <= b[n].hi for n in PARAMS)


def test_unit_points_map_linearly_or_log_uniformly_with_six_digits():
    space = (Bound("r0_rep_m", 10.0, 30.0, False), Bound("p_rep_ps", 0.01, 1.0, True))
    v = values([[0.0, 0.0], [0.5, 0.5], [1.0, 1.0], [0.25, 0.123456789]], space)
    assert v[:3].tolist() == [[10.0, 0.01], [20.0, 0.1], [30.0, 1.0]]  # log midpoint = geometric mean
    # 10^(-2 + 2 x 0.123456789) = 10^-1.75308642 = e^-4.0366298 = 0.01765690
    assert v[3, 0] == 15.0 and v[3, 1] == 0.0176569


def test_a_candidate_keeps_its_values_where_the_scenario_has_a_preset():
    """arena_v6 has preset paper_v6, which replaces a key left at its default: 25.6 is r0_rep_m's default."""
    params = scenario.load(ARENA6).params
    space = default_bounds()
    row = [25.6 if b.name == "r0_rep_m" else 0.5 * (b.lo + b.hi) for b in space]
    p = scenario.load(ARENA6, list(overrides(row, space, fixed_overrides(params)))).params
    assert p.r0_rep_m == 25.6 and (p.v_flock_mps, p.v_max_mps) == (6.0, 12.0)
    assert [getattr(p, b.name) for b in space] == pytest.approx(row)


def test_bounds_come_from_the_command_line_over_the_scenario_over_table3():
    space = {b.name: b for b in bounds([("c_frict", 0.1, 0.2)], {"c_frict": [0.01, 0.5], "r0_rep_m": [1, 100]}, "s")}
    assert (space["c_frict"].lo, space["c_frict"].hi, space["c_frict"].log) == (0.1, 0.2, False)
    assert (space["r0_rep_m"].lo, space["r0_rep_m"].hi, space["r0_rep_m"].log) == (1.0, 100.0, True)
    assert space["v_shill_mps"] == {b.name: b for b in default_bounds()}["v_shill_mps"]


def test_fitness_is_the_mean_mu_and_a_failed_run_counts_zero():
    rows = pd.DataFrame({"status": ["done", "done", "failed"], "mu": [0.9, 0.6, None]})
    assert fitness(rows) == pytest.approx(0.5)


def _scenario_with_bounds(tmp_path, table: str) -> pathlib.Path:
    text = ARENA4.read_text().replace('net = "../nets/arena.net.xml"', f'net = "{ROOT / "nets" / "arena.net.xml"}"')
    p = tmp_path / "arena.toml"
    p.write_text(text + "\n[tune.flocking]\n" + table + "\n")
    return p


@pytest.mark.parametrize("extra, key", [
    (["--bound", "r0_rep", "1", "2"], "--bound"),  # not a key (r0_rep_m is)
    (["--bound", "r0_rep_m", "5", "1"], "--bound"),
    (["--bound", "p_frict_ps", "0", "10"], "--bound"),  # the model needs p_frict > 0
    (["--bound", "c_frict", "a", "1"], "--bound"),
    (["--pop-size", "1"], "--pop-size"),
    (["--evals", "1"], "--evals"),
    (["--eval-first-seed", "100"], "--eval-first-seed"),  # overlaps the tuning seeds 101..103
    (["--start-from", "paper"], "--start-from"),  # random or scenario
    (["--set", "controllers.flocking.nope=1"], "controllers.flocking.nope"),
])
def test_bad_flocking_tune_input_is_one_line(tmp_path, extra, key):
    r = cli_in_process("tune", "flocking", ARENA4, *extra, "--out", tmp_path / "out")
    assert_refused(r, key, tmp_path / "out")


def test_a_bad_scenario_bound_is_one_line(tmp_path):
    scn = _scenario_with_bounds(tmp_path, "r0_rep_m = [40.0]")
    r = cli_in_process("tune", "flocking", scn, "--out", tmp_path / "out")
    assert_refused(r, "tune.flocking.r0_rep_m", tmp_path / "out")


def test_the_scenarios_parameters_map_into_the_unit_cube_as_the_bounds_are_searched():
    """arena_v6 runs with preset paper_v6 (Table 3 at 6 m/s); the default bounds (see the first test)."""
    params, space = scenario.load(ARENA6).params, default_bounds()
    w = warm_start(params, space)
    u = dict(zip(PARAMS, w.unit))
    # linear: r0_rep_m 41.1 in [11.525, 69.275]: 29.575 / 57.75 = 169/330
    assert u["r0_rep_m"] == pytest.approx(169 / 330, rel=1e-12) and u["r0_rep_m"] == pytest.approx(0.5121212)
    # log: p_frict_ps 5.32 in [0.05, 19.3923]: log10(106.4) / log10(387.846) = 2.026942 / 2.588660
    assert u["p_frict_ps"] == pytest.approx(math.log10(5.32 / 0.05) / math.log10(19.3923 / 0.05), rel=1e-12)
    assert u["p_frict_ps"] == pytest.approx(0.7830083, rel=1e-6)
    assert w.clipped == () and all(0 < x < 1 for x in w.unit)
    # back through the GA's own mapping: exactly the scenario's values (they have at most 6 digits)
    assert values([w.unit], space)[0].tolist() == [PRESETS["paper_v6"][n] for n in PARAMS]
    # outside its bounds: clipped to the nearer one (25.6 < 30 linear, 0.13 > 0.1 log), named in one line
    narrow = (Bound("r0_rep_m", 30.0, 40.0, False), Bound("p_rep_ps", 0.001, 0.1, True))
    c = warm_start(scenario.load(ARENA4).params, narrow)
    assert c.unit == (0.0, 1.0) and [x[0] for x in c.clipped] == ["r0_rep_m", "p_rep_ps"]
    assert c.note() == ("r0_rep_m = 25.6 lies outside its bounds [30, 40], clipped to 30; p_rep_ps = 0.13 lies "
                        "outside its bounds [0.001, 0.1], clipped to 0.1") and "\n" not in c.note()


def _toy_mu(cands) -> list[float]:
    """A made-up fitness of the 11 values, to drive the GA without SUMO: 1 / (1 + their sum)."""
    out = []
    for c in cands:
        kv = dict(s.rsplit("=", 1) for s in c)
        out.append(1.0 / (1.0 + sum(float(kv[f"controllers.flocking.{n}"]) for n in PARAMS)))
    return out


def _toy_search(start=None, generations=2, pop_size=4):
    fixed = fixed_overrides(scenario.load(ARENA4).params)
    hist, gens = search(_toy_mu, default_bounds(), fixed, generations, pop_size, 1, start=start)
    return pd.DataFrame(hist), pd.DataFrame(gens)


def test_a_warm_start_is_the_first_individual_of_generation_0_and_the_rest_is_as_without_it():
    space = default_bounds()
    cold, _ = _toy_search(generations=0, pop_size=5)
    warm, _ = _toy_search(warm_start(scenario.load(ARENA6).params, space), generations=0, pop_size=5)
    assert warm["generation"].tolist() == [0] * 5
    assert warm.loc[0, list(PARAMS)].tolist() == [PRESETS["paper_v6"][n] for n in PARAMS]
    assert warm.loc[1:, list(PARAMS)].equals(cold.loc[1:, list(PARAMS)])  # the same random draws
    assert not cold.loc[0, list(PARAMS)].equals(warm.loc[0, list(PARAMS)])


# generations.csv of _toy_search() as main made it before --start-from existed (c6975a9, pymoo 0.6.2)
MAIN_TOY_GENERATIONS = (
    "generation,evaluations,best_mu,mean_mu,worst_mu,r0_rep_m,p_rep_ps,r0_frict_m,c_frict,v_frict_mps,p_frict_ps,"
    "a_frict_mps2,r0_shill_m,v_shill_mps,p_shill_ps,a_shill_mps2\n"
    "0,4,0.006936772903505542,0.005481457045909628,0.004478945518918293,41.0827,0.433538,54.7611,0.316302,0.19099,"
    "0.623473,6.94401,6.95127,23.2812,0.18683,8.38784\n"
    "1,8,0.007386618497365284,0.006713101537303421,0.005677610095285382,41.0827,0.433538,54.7611,0.0350042,"
    "0.376793,0.623473,6.94401,6.95127,14.6042,0.180016,8.38784\n"
    "2,12,0.007416953124971955,0.007307166793853275,0.007034288675319287,41.0827,0.433538,54.7611,0.0350042,"
    "0.379492,0.623473,6.94401,6.95127,14.6773,0.180016,7.75835\n")


def test_start_from_random_is_the_search_main_made_before_the_warm_start():
    """The engine writes ``generations.csv`` as ``DataFrame(gens).to_csv(index=False)``: byte for byte."""
    assert _toy_search()[1].to_csv(index=False) == MAIN_TOY_GENERATIONS



def test_each_fitness_is_the_mean_of_its_runs_mu_in_the_ledger(tmp_path):
    scn = _scenario_with_bounds(tmp_path, "r0_rep_m = [20.0, 30.0]")
    out = tmp_path / "out"
    assert main(["tune", "flocking", str(scn), *TINY, "--workers", "1", "--out", str(out)]) == 0
    hist = pd.read_csv(out / "history.csv")
    led = ledger.read(out / "ledger.sqlite")
    assert len(led) == TINY_RUNS and (led["status"] == "done").all()
    assert hist["r0_rep_m"].between(20.0, 30.0).all()  # the scenario's bound
    fixed = fixed_overrides(scenario.load(scn).params)
    space = bounds([], {"r0_rep_m": [20.0, 30.0]}, str(scn))
    by_overrides = {tuple(json.loads(o)): g for o, g in led.groupby("overrides")}
    for _, c in hist.iterrows():
        runs = by_overrides[(*SETS, "output.plots=false", *overrides([c[n] for n in PARAMS], space, fixed))]
        runs = runs[runs["seed"] >= 101]  # the best candidate also ran on the fresh seeds 1, 2
        assert sorted(runs["seed"]) == [101, 102]
        assert c["mu"] == pytest.approx(runs["mu"].mean(), rel=1e-9)
    assert hist["mu"].nunique() > 1 and hist["mu"].max() > 0  # the candidates differ
    gens = pd.read_csv(out / "generations.csv")
    for g in gens.itertuples():  # elitism: the population's best is the best candidate evaluated so far
        assert g.best_mu == pytest.approx(hist.loc[hist["generation"] <= g.generation, "mu"].max())
    stats = json.loads((out / "statistics.json").read_text())
    ev = pd.read_csv(out / "evaluations.csv")
    assert ev["seed"].tolist() == [1, 2] == stats["eval_seeds"]
    assert stats["mu_mean"] == pytest.approx(ev["tuned_mu"].mean()) and stats["mu_max"] == ev["tuned_mu"].max()
    assert stats["n_above_mean"] == int((hist["mu"] >= stats["mu_mean"]).sum())
    tuned = scenario.read_toml(out / "tuned.toml")["controllers"]["flocking"]
    best = hist.loc[hist["mu"].idxmax()]
    assert all(tuned[n] == best[n] for n in PARAMS) and tuned["v_flock_mps"] == 4.0


def test_start_from_random_writes_the_default_runs_files_and_runs_nothing_new(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["tune", "flocking", str(ARENA4), *TINY, "--workers", "1", "--out", str(a)]) == 0
    before = ledger.row_hashes(a / "ledger.sqlite")
    assert main(["tune", "flocking", str(ARENA4), *TINY, "--start-from", "random", "--workers", "1", "--ledger",
                 str(a / "ledger.sqlite"), "--out", str(b)]) == 0
    assert ledger.row_hashes(a / "ledger.sqlite") == before  # the same candidates: every run from the ledger
    for name in ("generations.csv", "history.csv", "tuned.toml", "evaluations.csv", "statistics.json"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    assert "--start-from" not in (b / "tuned.toml").read_text()  # the default, recorded as before


def test_a_warm_started_search_resumes_after_sigkill_to_the_same_files(tmp_path, capsys):
    """paper_v4's r0_rep_m 25.6 lies below the bound 30..40: clipped, one line on stderr."""
    a, b = tmp_path / "a", tmp_path / "b"
    warm = [*TINY, "--start-from", "scenario", "--bound", "r0_rep_m", "30", "40", "--workers", "1"]
    capsys.readouterr()
    assert main(["tune", "flocking", str(ARENA4), *warm, "--out", str(a)]) == 0
    err = capsys.readouterr().err
    assert err == ("tune: --start-from scenario: r0_rep_m = 25.6 lies outside its bounds [30, 40], clipped to "
                   "30\n"), err
    hist = pd.read_csv(a / "history.csv")
    assert hist.loc[0, list(PARAMS)].tolist() == [30.0 if n == "r0_rep_m" else PRESETS["paper_v4"][n]
                                                  for n in PARAMS]
    assert json.loads((a / "statistics.json").read_text())["command"].endswith("--start-from scenario")
    sigkill_at(["tune", "flocking", str(ARENA4), *warm, "--out", str(b)], b / "ledger.sqlite", 10)
    before = ledger.row_hashes(b / "ledger.sqlite")
    assert 10 <= len(before) < 16 and not (b / "generations.csv").exists()
    assert main(["tune", "flocking", str(ARENA4), *warm, "--out", str(b)]) == 0
    after = ledger.row_hashes(b / "ledger.sqlite")
    assert len(after) == TINY_RUNS and all(after[k] == h for k, h in before.items())
    for name in ("generations.csv", "history.csv", "tuned.toml", "evaluations.csv", "statistics.json"):
        assert (a / name).read_text() == (b / name).read_text(), name


def test_flocking_tuner_resumes_after_sigkill_mid_generation_to_the_same_files(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["tune", "flocking", str(ARENA4), *TINY, "--workers", "1", "--out", str(a)]) == 0
    assert ledger_rows(a / "ledger.sqlite") == TINY_RUNS
    # generation 0 is runs 1-8, generation 1 runs 9-16: killed inside generation 1
    sigkill_at(["tune", "flocking", str(ARENA4), *TINY, "--workers", "1", "--out", str(b)], b / "ledger.sqlite", 10)
    before = ledger.row_hashes(b / "ledger.sqlite")
    assert 10 <= len(before) < 16 and not (b / "generations.csv").exists()
    assert main(["tune", "flocking", str(ARENA4), *TINY, "--workers", "1", "--out", str(b)]) == 0
    after = ledger.row_hashes(b / "ledger.sqlite")
    assert len(after) == TINY_RUNS and all(after[k] == h for k, h in before.items())  # finished runs not re-run
    for name in ("generations.csv", "history.csv", "tuned.toml", "evaluations.csv", "statistics.json"):
        assert (a / name).read_text() == (b / name).read_text(), name
    gens = pd.read_csv(b / "generations.csv")
    assert gens["generation"].tolist() == [0, 1] and np.all(np.isfinite(gens["best_mu"]))
    assert (b / "convergence.png").stat().st_size > 10_000 and not math.isnan(gens["mean_mu"].iloc[-1])
