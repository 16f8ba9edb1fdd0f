"""The numba kernels' sort and search helpers give numpy's results exactly: a stable sort's
permutation (ties in their original order), the sorted values, and numpy's insertion points."""
from __future__ import annotations

import numpy as np
import pytest

from sumo_avoid.core.compiled import searchsorted, sorted_copy, stable_argsort


def test_by_hand():
    x = np.array([2.0, 1.0, 2.0, 0.5, 1.0])
    assert stable_argsort(x).tolist() == [3, 1, 4, 0, 2]  # the two 1.0 and the two 2.0 keep their order
    assert sorted_copy(np.array([3, 1, 2], np.int64)).tolist() == [1, 2, 3]
    a = np.array([1.0, 2.0, 2.0, 3.0])
    assert [searchsorted(a, 2.0, False), searchsorted(a, 2.0, True)] == [1, 3]
    assert [searchsorted(a, 0.0, False), searchsorted(a, 9.0, True)] == [0, 4]
    assert stable_argsort(np.zeros(0)).tolist() == [] and searchsorted(np.zeros(0), 1.0, True) == 0


@pytest.mark.parametrize("seed", range(20))
def test_same_as_numpy_on_random_arrays_with_ties(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 200))
    x = rng.integers(0, 12, n) * 0.25  # many ties
    assert np.array_equal(stable_argsort(x), np.argsort(x, kind="stable"))
    assert np.array_equal(sorted_copy(x), np.sort(x))
    ints = rng.permutation(n).astype(np.int64)
    assert np.array_equal(sorted_copy(ints), np.sort(ints))
    a = np.sort(x)
    for v in rng.integers(-1, 14, 20) * 0.25:
        assert searchsorted(a, v, False) == np.searchsorted(a, v, side="left")
        assert searchsorted(a, v, True) == np.searchsorted(a, v, side="right")
