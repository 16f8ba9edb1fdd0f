"""The metric interface: one abstract ``compute`` over a finished run's recording (waymax-style).

A metric never runs inside the loop and never feeds back; it reads
:class:`~sumo_avoid.rollout.result.RunResult` (the recorded table, SUMO's collision reports, the
scene, the plug-ins' counters) and returns a few ``metrics.json`` keys, the ones it declares
(``keys``, :class:`~sumo_avoid.core.types.Keys`; checked against real runs by
tests/metrics/test_metric_keys.py). Values several metrics share (phi_coll, phi_wall) are computed
once per run with ``run.memo``.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from sumo_avoid.core.types import Keys
from sumo_avoid.rollout.result import RunResult


class Metric(ABC):
    """One group of ``metrics.json`` keys (registered by name in :data:`sumo_avoid.metrics.METRICS`)."""

    keys: ClassVar[Keys]  # the keys compute() writes

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        if not isinstance(getattr(cls, "keys", None), Keys):
            raise TypeError(f"metric {cls.__name__} declares no keys: give it keys = Keys(numeric=(...), nested=(...), text=(...)), "
                            "the metrics.json keys its compute() writes")

    @classmethod
    def keys_for(cls, scn: Any, stats: Keys) -> Keys:
        """The keys written in a run of scenario ``scn`` whose plug-ins' ``stats()`` write ``stats``
        (:func:`sumo_avoid.runs.declared.metric_keys`); a metric whose keys depend on them overrides this."""
        return cls.keys

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
