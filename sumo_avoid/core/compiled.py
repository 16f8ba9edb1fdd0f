"""Small numba helpers the compiled kernels share (sensing/occlusion.py, planning/kernels.py).

They stand in for numba's own np.sort / np.argsort / np.searchsorted, which cost seconds of compile
time in every kernel that uses them (the radar's first compile takes less than half the CPU time
without them), and give the same results: a stable sort's permutation is unique, the sorted values
do not depend on
the algorithm (finite values), and a binary search finds numpy's insertion point.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def sorted_copy(a):
    """A new array of a's values in ascending order (merge sort; for finite values exactly np.sort's)."""
    idx = stable_argsort(a)
    out = np.empty(a.shape[0], a.dtype)
    for i in range(a.shape[0]):
        out[i] = a[idx[i]]
    return out


@njit(cache=True)
def stable_argsort(x):
    """Indices that sort x ascending, equal values in their original order (np.argsort kind='stable')."""
    n = x.shape[0]
    idx = np.empty(n, np.int64)
    for i in range(n):
        idx[i] = i
    width = 1
    tmp = np.empty(n, np.int64)
    while width < n:  # bottom-up merge sort
        for lo in range(0, n, 2 * width):
            mid, hi = min(lo + width, n), min(lo + 2 * width, n)
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                if x[idx[j]] < x[idx[i]]:
                    tmp[k] = idx[j]
                    j += 1
                else:
                    tmp[k] = idx[i]
                    i += 1
                k += 1
            while i < mid:
                tmp[k] = idx[i]
                i += 1
                k += 1
            while j < hi:
                tmp[k] = idx[j]
                j += 1
                k += 1
        idx, tmp = tmp, idx
        width *= 2
    return idx


@njit(cache=True)
def searchsorted(a, v, right):
    """np.searchsorted(a, v, side="right" if right else "left") on ascending a: a binary search."""
    lo, hi = 0, a.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if a[mid] < v or (right and a[mid] == v):
            lo = mid + 1
        else:
            hi = mid
    return lo
