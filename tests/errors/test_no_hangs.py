"""Nothing hangs on bad input (issue 17 item 3): what crosses a process boundary survives pickling,
a failing pool job comes back as a plain record, unbounded ranges are refused at once."""
from __future__ import annotations

import pickle
import time

import pytest

from sumo_avoid.core.config import ScenarioError, ScenarioErrors
from sumo_avoid.studies import batch, reproduce
from sumo_avoid.sumo.inputs import InputError


@pytest.mark.parametrize("err", [
    ScenarioError("a.toml", "sim.seed", "an integer", 1.5),
    ScenarioErrors([ScenarioError("a.toml", "x", "y", show_got=False), ScenarioError("b.toml", "z", "w", 3)]),
    InputError("/n.net.xml", "not well-formed XML", "vehicle 'ego'"),
])
def test_errors_survive_pickling_whole(err):
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is type(err) and str(back) == str(err)


def test_a_failing_reproduce_job_is_a_plain_record_not_an_exception():
    """In a pool worker an exception the parent cannot unpickle left `reproduce` waiting for ever."""
    job = {"v": 4, "seed": 1, "agents": 3, "duration": 1.0, "sets": ["controllers.flocking.nope=1"], "figure": None}
    rec = reproduce._safe_job(job)
    assert rec["v"] == 4 and rec["seed"] == 1
    assert rec["error"].startswith("ScenarioError: ") and "controllers.flocking.nope" in rec["error"]
    pickle.loads(pickle.dumps(rec))


def test_an_unbounded_seed_range_is_refused_at_once():
    t0 = time.perf_counter()
    for text in ("0-1000000000", "2147483648", "0-99999,100000-100001"):
        with pytest.raises(ScenarioError, match="at most 100000 seeds in"):
            batch.parse_seeds(text)
    assert time.perf_counter() - t0 < 1.0
    assert batch.parse_seeds("2147483640-2147483647") == tuple(range(2147483640, 2147483648))
