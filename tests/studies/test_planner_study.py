"""The planner study table on a hand-made run folder (no SUMO): driven path against the visibility-graph
reference, and the share of plans usable by generation 20."""
import json

import pandas as pd
import pytest

from sumo_avoid.studies.planner_study import study_table, summary


def test_study_table_compares_driven_with_the_reference(tmp_path):
    run = tmp_path / "runs" / "abc"
    run.mkdir(parents=True)
    (run / "metrics.json").write_text(json.dumps({"seed": 3, "controller": "ga_planner", "goal_reached": True,
                                                  "collisions": 0, "phi_wall": 0.0, "path_length_m": 12.0,
                                                  "per_ego": {"e": {"path_length_m": 12.0}}}))
    pd.DataFrame({"step": [1, 2], "id": ["e", "e"], "is_ego": [True, True], "x": [0.0, 1.0],
                  "y": [0.0, 0.0]}).to_csv(run / "trajectories.csv", index=False)
    pd.DataFrame({"ego": ["e", "e"], "generation_usable": [3, -1],
                  "path": ["0 0;5 5;10 0", "1 0;10 0"]}).to_csv(run / "plans.csv", index=False)
    square = [[[4.0, -1.0], [6.0, -1.0], [6.0, 1.0], [4.0, 1.0]]]
    df, plans = study_table(tmp_path, square, 0.0)
    ref = 2 * (4**2 + 1) ** 0.5 + 2  # over the square's corners
    assert df.loc[0, "reference_m"] == pytest.approx(ref)
    assert df.loc[0, "ratio"] == pytest.approx(12.0 / ref)
    assert df.loc[0, "usable_within_20"] == 0.5 and len(plans) == 2
    text = summary(df, plans)
    assert "goal reached 1/1" in text and "usable (collision-free) by generation 20: 1 (50.0%); never: 1" in text
