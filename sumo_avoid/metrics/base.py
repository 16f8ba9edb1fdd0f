"""The metric interface: one abstract ``compute`` over a finished run's recording (waymax-style).

A metric never runs inside the loop and never feeds back; it reads
:class:`~sumo_avoid.rollout.result.RunResult` (the recorded table, SUMO's collision reports, the
scene, the plug-ins' counters) and returns a few ``metrics.json`` keys. Values several metrics
share (phi_coll, phi_wall) are computed once per run with ``run.memo``.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from sumo_avoid.rollout.result import RunResult


class Metric(ABC):
    """One group of ``metrics.json`` keys (registered by name in :data:`sumo_avoid.metrics.METRICS`)."""

    @abstractmethod
    def compute(self, run: RunResult) -> dict:
        ...


def clean(x):
    """JSON-ready: numpy scalars to Python, non-finite floats to None, keys to str (recursively)."""
    if isinstance(x, dict):
        return {str(k): clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [clean(v) for v in x]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, np.bool_):
        return bool(x)
    return x
