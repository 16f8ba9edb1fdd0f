import numpy as np
import pandas as pd

from sumo_avoid.metrics.ego_rows import EgoRows


def test_ego_rows_codes_and_order_by_id_then_step():
    t = pd.DataFrame({"step": [1, 0, 1, 0, 0, 2], "id": ["b", "b", "car", "a10", "a9", "a9"],
                      "is_ego": [True, True, False, True, True, True]})
    e = EgoRows.of(t)
    assert e.ids.tolist() == ["a10", "a9", "b"]  # text order, not number order
    assert e.code.tolist() == [2, 2, 0, 1, 1]  # the ego rows in table order: b, b, a10, a9, a9
    ref = e.table.reset_index(drop=True).sort_values(["id", "step"], kind="stable").index.to_numpy()
    np.testing.assert_array_equal(e.by_id(), ref)
    assert e.table["id"].iloc[e.by_id()].tolist() == ["a10", "a9", "a9", "b", "b"]
