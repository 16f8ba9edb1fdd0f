"""The figures of a run by declaration (runs/declared.py, plots.PLOTS): the standard ones, ``arena``
for a scene with walls or obstacles, and what the controller declares (``plots``)."""
from __future__ import annotations

import pytest

from sumo_avoid.plots import PLOTS
from sumo_avoid.runs import runner
from sumo_avoid.runs.declared import plot_names
from sumo_avoid.runs.outputs import write_outputs
from sumo_avoid.scenario import spec as scenario
from tests.conftest import SCENARIOS


def test_plots_come_from_the_scene_and_the_controller_s_declaration():
    assert plot_names(scenario.load(SCENARIOS / "overtaking.toml")) == ("trajectory", "timeseries")
    assert plot_names(scenario.load(SCENARIOS / "arena_obstacles.toml")) == ("trajectory", "timeseries", "arena")
    assert plot_names(scenario.load(SCENARIOS / "planner" / "field.toml")) == ("trajectory", "timeseries", "arena",
                                                                               "plans")
    assert plot_names(scenario.load(SCENARIOS / "formation" / "gap.toml")) == ("trajectory", "timeseries", "arena",
                                                                             "formation")
    assert set(PLOTS) == {"trajectory", "timeseries", "arena", "plans", "formation"}


@pytest.mark.sumo
@pytest.mark.parametrize("name, pngs", [
    ("overtaking.toml", {"trajectory.png", "timeseries.png"}),
    ("formation/gap.toml", {"trajectory.png", "timeseries.png", "arena.png", "formation.png"}),
])
def test_a_run_writes_the_declared_figures_and_no_other(tmp_path, name, pngs):
    res = runner.run(scenario.load(SCENARIOS / name, ["sim.duration_s=2"]))
    write_outputs(res, tmp_path)
    assert {p.name for p in tmp_path.glob("*.png")} == pngs
    assert all((tmp_path / p).stat().st_size > 5000 for p in pngs)
