"""Nothing hangs on bad input (issue 17 item 3): what crosses a process boundary survives pickling,
a failing pool job comes back as a plain record, unbounded ranges are refused at once."""
from __future__ import annotations

import pickle
import time

import pytest

from sumo_avoid.core.config import ScenarioError, ScenarioErrors
from sumo_avoid.runs import worker
from sumo_avoid.studies import batch, table4
from sumo_avoid.sumo.inputs import InputError


@pytest.mark.parametrize("err", [
    ScenarioError("a.toml", "sim.seed", "an integer", 1.5),
    ScenarioErrors([ScenarioError("a.toml", "x", "y", show_got=False), ScenarioError("b.toml", "z", "w", 3)]),
    InputError("/n.net.xml", "not well-formed XML", "vehicle 'ego'"),
])
def test_errors_survive_pickling_whole(err):
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err) and str(back) == str(err)


@pytest.mark.sumo  # a run's child process (it fails before SUMO starts)
def test_a_failing_reproduce_run_is_a_plain_outcome_not_an_exception(tmp_path):
    """A run's failure crosses the process boundary as data (an exception the parent cannot unpickle
    once left `reproduce` waiting for ever)."""
    job = table4.table4_job(4, 1, agents=3, duration=1.0, sets=["controllers.flocking.nope=1"])
    res = worker.run_in(tmp_path, job, 120)
    assert res.status == "failed" and res.metrics is None
    assert res.error.startswith("ScenarioError: ") and "controllers.flocking.nope" in res.error
    pickle.loads(pickle.dumps(res))


def test_an_unbounded_seed_range_is_refused_at_once():
    t0 = time.perf_counter()
    for text in ("0-1000000000", "2147483648", "0-99999,100000-100001"):
        with pytest.raises(ScenarioError, match="at most 100000 seeds in"):
            batch.parse_seeds(text)
    assert time.perf_counter() - t0 < 1.0
    assert batch.parse_seeds("2147483640-2147483647") == tuple(range(2147483640, 2147483648))
