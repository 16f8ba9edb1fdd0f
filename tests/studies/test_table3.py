"""``sumo-avoid reproduce table3``: a tiny version on real libsumo (5 vehicles, 3 s, a population of 3 over
one generation) writes Table 3 beside the paper's numbers from the per-speed tunings; bad flags as one line."""
from __future__ import annotations

import json

import pandas as pd
import pytest
from conftest import assert_refused, cli_in_process

from sumo_avoid.cli import main
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
])
def test_bad_table3_input_is_one_line(tmp_path, extra, key):
    r = cli_in_process("reproduce", "table3", *extra, "--out", tmp_path / "out")
    assert_refused(r, key, tmp_path / "out")
