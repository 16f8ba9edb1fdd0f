"""Studies on a Dask cluster give what the local pool gives: a batch (its metrics, run by run) and
a tiny formation-gain search and a tiny flocking GA (their histories, generations and tuned parameters,
bit for bit). One test, one cluster:
starting a cluster costs its workers' imports and fork servers, and pytest-xdist could give two
tests of this file to two workers."""
from __future__ import annotations

from conftest import GAP, METRIC_COLS, OVERTAKING, SCENARIOS, SHORT, TINY_TUNE
from dask.distributed import LocalCluster

from sumo_avoid.cli import main
from sumo_avoid.studies import batch, ledger

# the flocking GA: generation 0 of 2 candidates on one seed, then 2 fresh seeds x (best, scenario's): 6 runs
FLOCK = ["tune", "flocking", str(SCENARIOS / "arena_v4.toml"), "--generations", "0", "--pop-size", "2", "--seeds", "1",
         "--evals", "2", "--set", "arena.n_agents=5", "--set", "arena.initial_speed_mps=4.0", "--set",
         "sim.duration_s=3", "--quiet"]


def test_batch_and_tuner_on_a_dask_cluster_equal_the_local_pool(tmp_path):
    specs = batch.expand([OVERTAKING], [1, 2], SHORT, ["apf_sa", "apf"])
    local = batch.BatchConfig(tuple(specs), tmp_path / "local" / "ledger.sqlite", workers=2)
    assert batch.run_batch(local, progress=False)["done"] == 4
    assert main(["tune", "formation", str(GAP), *TINY_TUNE, "--workers", "2", "--out", str(tmp_path / "tune_local")]) == 0
    assert main([*FLOCK, "--workers", "2", "--out", str(tmp_path / "flock_local")]) == 0
    with LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None,
                      processes=True) as cluster:
        assert main(["batch", str(OVERTAKING), "--seeds", "1-2", "--controller", "apf_sa", "--controller", "apf",
                     *sum((["--set", s] for s in SHORT), []), "--scheduler", cluster.scheduler_address,
                     "--ledger", str(tmp_path / "dask" / "ledger.sqlite"), "--quiet"]) == 0
        assert main(["tune", "formation", str(GAP), *TINY_TUNE, "--scheduler", cluster.scheduler_address,
                     "--out", str(tmp_path / "tune_dask")]) == 0
        assert main([*FLOCK, "--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "flock_dask")]) == 0
    a = ledger.read(local.ledger).set_index("key")
    b = ledger.read(tmp_path / "dask" / "ledger.sqlite").set_index("key")
    assert sorted(a.index) == sorted(b.index) == sorted(s.key for s in specs)
    cols = METRIC_COLS + ["sa_escapes", "time_to_goal_s"]
    assert a[cols].sort_index().equals(b[cols].sort_index())
    for name in ("history.csv", "tuned.toml"):
        assert (tmp_path / "tune_local" / name).read_text() == (tmp_path / "tune_dask" / name).read_text()
    for name in ("generations.csv", "history.csv", "tuned.toml", "evaluations.csv", "statistics.json"):
        assert (tmp_path / "flock_local" / name).read_text() == (tmp_path / "flock_dask" / name).read_text()
