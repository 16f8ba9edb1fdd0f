"""``sumo-avoid tune formation``: the gain mapping and the score by hand, bad input as one line, and
on real libsumo a tiny search that resumes after SIGKILL to the same result (the same search on a
Dask cluster: tests/studies/test_dask.py)."""
from __future__ import annotations

import pandas as pd
import pytest
from conftest import GAP, TINY_TUNE, assert_refused, cli_in_process, ledger_rows, sigkill_at

from sumo_avoid.cli import main
from sumo_avoid.studies import ledger
from sumo_avoid.studies.tune_formation import FAILED_SCORE, gains, score


def test_gains_are_log_uniform_with_six_digits():
    g = gains([[0.0, 1.0], [0.5, 0.5], [1.0, 0.0]], (0.002, 0.2), (0.02, 2.0))
    assert g == [(0.002, 2.0), (0.02, 0.2), (0.2, 0.02)]  # the log midpoint of 0.002..0.2 is 0.02
    assert gains([[0.123456789, 0.0]], (1.0, 10.0), (1.0, 2.0))[0][0] == 1.32879  # 10^0.123456789 = e^(2.302585 x 0.123456789) = e^0.2842698 = 1.328794


def test_score_means_penalised_runs_and_fails_high():
    rows = pd.DataFrame({"status": ["done", "done", "failed"], "s_ef": [1.5, 1.0, None],
                         "collisions": [0, 2, 0], "obstacle_hits": [1, 0, 0]})
    assert score(rows, 0.5) == pytest.approx(((1.5 + 0.5) + (1.0 + 1.0) + FAILED_SCORE) / 3)


@pytest.mark.parametrize("args, key", [
    (["tune", "planner", GAP], "controller"),
    (["tune", "formation", GAP, "--nests", "1"], "--nests"),
    (["tune", "formation", GAP, "--beta", "2.5"], "--beta"),
    (["tune", "formation", GAP, "--eta-at", "0.5", "0.1"], "--eta-at"),
    (["tune", "formation", GAP, "--set", "controllers.formation.nope=1"], "controllers.formation.nope"),
])
def test_bad_tune_input_is_one_line(tmp_path, args, key):
    r = cli_in_process(*args, "--out", tmp_path / "out")
    assert_refused(r, key, tmp_path / "out")



def test_tuner_resumes_after_sigkill_to_the_same_result(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert main(["tune", "formation", str(GAP), *TINY_TUNE, "--workers", "2", "--out", str(a)]) == 0
    # 3 nests x 2 seeds initial, 3 x 2 Levy eggs, round(0.75) = 1 x 2 abandoned: 14 runs
    assert ledger_rows(a / "ledger.sqlite") == 14
    sigkill_at(["tune", "formation", str(GAP), *TINY_TUNE, "--workers", "2", "--out", str(b)], b / "ledger.sqlite", 4)
    before = ledger.row_hashes(b / "ledger.sqlite")
    assert 4 <= len(before) < 14 and not (b / "tuned.toml").exists()
    assert main(["tune", "formation", str(GAP), *TINY_TUNE, "--workers", "2", "--out", str(b)]) == 0
    after = ledger.row_hashes(b / "ledger.sqlite")
    assert len(after) == 14 and all(after[k] == h for k, h in before.items())  # finished runs not re-run
    assert (a / "tuned.toml").read_text() == (b / "tuned.toml").read_text()
    assert (a / "history.csv").read_text() == (b / "history.csv").read_text()
    assert (b / "convergence.png").stat().st_size > 10_000
