"""plans.png and convergence.png from a hand-made plan log (no SUMO)."""
import numpy as np
import pandas as pd

from sumo_avoid.plots.planner import (
    parse_fitness,
    parse_path,
    plot_convergence,
    plot_plans,
)
from sumo_avoid.rollout.result import Scene


def _log():
    return pd.DataFrame({"ego": ["e", "e"], "time_s": [0.1, 2.0], "trigger": ["takeover", "new_obstacle"],
                         "generations": [2, 1], "generation_usable": [1, -1], "usable": [True, False],
                         "clearance_m": [4.0, 1.0], "path_length_m": [20.0, 21.0], "known_points": [0, 2],
                         "plan_ms": [3.0, 4.0], "best_fitness": ["0.5;0.7;0.9", "0.2;0.3"],
                         "path": ["0.000 0.000;10.000 5.000;20.000 0.000", "1.000 0.000;20.000 0.000"]})


def test_logged_paths_and_fitness_parse_back():
    assert parse_path("0.000 0.000;10.000 5.000;20.000 0.000").tolist() == [[0, 0], [10, 5], [20, 0]]
    assert parse_fitness("0.5;0.7;0.9").tolist() == [0.5, 0.7, 0.9]


def test_plan_plots_write_pngs(tmp_path):
    rmap = pd.DataFrame({"ego": ["e", "e"], "time_s": [1.0, 1.0], "x": [10.0, 11.0], "y": [1.0, 1.0],
                         "is_return": [True, False]})
    traj = pd.DataFrame({"step": [1, 2, 3], "id": ["e"] * 3, "x": [0.0, 5.0, 10.0], "y": [0.0, 1.0, 2.0]})
    scene = Scene(None, np.array([[-5.0, -5.0], [25.0, -5.0], [25.0, 15.0], [-5.0, 15.0]]),
                  (np.array([[9.0, 1.0], [12.0, 1.0], [12.0, 3.0]]),))
    plot_plans(_log(), rmap, traj, scene, tmp_path / "plans.png", "t")
    plot_convergence(_log(), tmp_path / "convergence.png", "t")
    assert (tmp_path / "plans.png").stat().st_size > 5000 and (tmp_path / "convergence.png").stat().st_size > 5000
