"""``sumo-avoid tune flocking``: the GA's search space by hand (Table 3's hull widened, log scaling),
the candidates' overrides against the scenario's preset, bad input as one line, and on real libsumo
a tiny search: each candidate's fitness is the mean of its runs' μ in the ledger, the population best
never falls (elitism), and a search killed with SIGKILL mid-generation resumes to the same files."""
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
                                              overrides, values)

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
    (["--set", "controllers.flocking.nope=1"], "controllers.flocking.nope"),
])
def test_bad_flocking_tune_input_is_one_line(tmp_path, extra, key):
    r = cli_in_process("tune", "flocking", ARENA4, *extra, "--out", tmp_path / "out")
    assert_refused(r, key, tmp_path / "out")


def test_a_bad_scenario_bound_is_one_line(tmp_path):
    scn = _scenario_with_bounds(tmp_path, "r0_rep_m = [40.0]")
    r = cli_in_process("tune", "flocking", scn, "--out", tmp_path / "out")
    assert_refused(r, "tune.flocking.r0_rep_m", tmp_path / "out")



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
