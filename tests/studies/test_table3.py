"""``sumo-avoid reproduce table3``: a tiny version on real libsumo (5 vehicles, 3 s, a population of 3 over
one generation) writes Table 3 beside the paper's numbers from the per-speed tunings; ``--start-from`` goes
through to each speed's tuner (a tiny warm-started speed starts from the paper's parameters); bad flags as
one line."""
from __future__ import annotations

import json

import pandas as pd
import pytest
from conftest import assert_refused, cli_in_process

from sumo_avoid.cli import _parser, main
from sumo_avoid.control.flocking.terms import PRESETS
from sumo_avoid.studies import table3
from sumo_avoid.studies.tune_flocking import PARAMS

TINY = ["--agents", "5", "--duration", "3", "--generations", "1", "--pop-size", "3", "--tune-seeds", "1",
        "--seeds", "2", "--set", "arena.initial_speed_mps=4.0", "--workers", "1"]


def test_tiny_table3_puts_each_speeds_tuning_beside_the_paper(tmp_path):
    out = tmp_path / "t3"
    assert main(["reproduce", "table3", *TINY, "--out", str(out)]) == 0
    df = pd.read_csv(out / "table3.csv")
    assert sorted(df["v_flock"].unique()) == [4, 6, 8]
    cell = df.set_index(["v_flock", "quantity"])
    # the paper's Table 3 (SPEC §1.4): mu and the GA-optimised values with their working ranges
    assert (cell.loc[(4, "mu_max"), "paper"], cell.loc[(6, "mu_mean"), "paper"], cell.loc[(8, "mu_sd"), "paper"]) == (
        0.918, 0.776, 0.075)
    assert tuple(cell.loc[(6, "r0_rep_m"), ["paper", "paper_lo", "paper_hi"]]) == (41.1, 30.8, 51.0)
    assert tuple(cell.loc[(8, "a_frict_mps2"), ["paper", "paper_lo", "paper_hi"]]) == (0.98, 0.0, 2.89)
    for v in (4, 6, 8):
        ev = pd.read_csv(out / f"v{v}" / "evaluations.csv")
        hist = pd.read_csv(out / f"v{v}" / "history.csv")
        assert ev["seed"].tolist() == [1, 2] and len(hist) == 6  # R fresh seeds; 3 + 3 candidates
        assert cell.loc[(v, "mu_mean"), "ours"] == pytest.approx(ev["tuned_mu"].mean())
        assert cell.loc[(v, "mu_max"), "ours"] == pytest.approx(ev["tuned_mu"].max())
        assert cell.loc[(v, "paper_params_mu_mean"), "ours"] == pytest.approx(ev["baseline_mu"].mean())
        assert cell.loc[(v, "n_above_mean"), "ours"] == (hist["mu"] >= ev["tuned_mu"].mean()).sum()
        best = hist.loc[hist["mu"].idxmax()]
        assert [cell.loc[(v, n), "ours"] for n in PARAMS] == pytest.approx([best[n] for n in PARAMS])
        s = json.loads((out / f"v{v}" / "statistics.json").read_text())
        assert s["mu_mean"] == pytest.approx(ev["tuned_mu"].mean())
    md = (out / "table3.md").read_text()
    for v, paper in ((4, 0.812), (6, 0.776), (8, 0.728)):
        ours = cell.loc[(v, "mu_mean"), "ours"]
        word = "reaches" if ours >= paper else "misses"
        assert f"v_flock {v}: μ̄ {ours:.3f} {word} the paper's {paper:.3f} ({ours - paper:+.3f})" in md
    assert "--pop-size 3" in md and (out / "convergence.png").stat().st_size > 10_000


@pytest.mark.parametrize("extra, key", [
    (["--generations", "-1"], "--generations"),
    (["--pop-size", "1"], "--pop-size"),
    (["--seeds", "1"], "--evals"),  # R fresh seeds: at least 2 (a mean and an sd)
    (["--tune-first-seed", "5"], "--eval-first-seed"),  # the tuning seeds 5..7 overlap the fresh seeds 1..20
    (["--set", "controllers.flocking.nope=1"], "controllers.flocking.nope"),
    (["--start-from", "paper"], "--start-from"),  # random or scenario
])
def test_bad_table3_input_is_one_line(tmp_path, extra, key):
    r = cli_in_process("reproduce", "table3", *extra, "--out", tmp_path / "out")
    assert_refused(r, key, tmp_path / "out")


def test_table3_passes_start_from_to_each_speeds_tuner(tmp_path):
    for given, want in (([], "random"), (["--start-from", "scenario"], "scenario")):
        args = _parser().parse_args(["reproduce", "table3", *given])
        assert [table3.tune_args(args, v, tmp_path).start_from for v in (4, 6, 8)] == [want] * 3


def test_a_tiny_warm_started_table3_starts_from_the_papers_parameters(tmp_path):
    out = tmp_path / "t3"
    assert main(["reproduce", "table3", *TINY, "--speeds", "4", "--start-from", "scenario", "--out", str(out)]) == 0
    hist = pd.read_csv(out / "v4" / "history.csv")
    assert len(hist) == 6 and hist.loc[0, list(PARAMS)].tolist() == [PRESETS["paper_v4"][n] for n in PARAMS]
    assert json.loads((out / "v4" / "statistics.json").read_text())["command"].endswith("--start-from scenario")
    md = (out / "table3.md").read_text()
    assert "--start-from scenario --out" in md and "generation 0 warm-started with the paper's parameters" in md
