import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"


@pytest.fixture
def scenario_path():
    return lambda name: SCENARIOS / f"{name}.toml"


def run_scenario(name: str, **kw):
    """Run a real scenario in real SUMO (libsumo) and return (RunResult, metrics dict)."""
    from sumo_avoid import outputs as evaluate
    from sumo_avoid.rollout import runner
    from sumo_avoid.scenario import spec as scenario

    scn = scenario.load(SCENARIOS / f"{name}.toml", kw.pop("overrides", []), **kw)
    res = runner.run(scn)
    return res, evaluate.compute(res)
