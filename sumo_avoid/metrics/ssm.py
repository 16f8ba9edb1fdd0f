"""Surrogate safety from SUMO's SSM device on the egos (:mod:`sumo_avoid.sumo.ssm_device`): the run's
smallest TTC and PET and largest DRAC over the conflicts SUMO logged, and their count.

SUMO logs an encounter only when one of its measures crosses the device's threshold, so the
extremes are clamped at the thresholds, which makes them exact and always defined:

    min_ttc_s     = min(TTC threshold, smallest minTTC logged)   = min(threshold, true min TTC)
    min_pet_s     = min(PET threshold, smallest PET logged)
    max_drac_mps2 = max(DRAC threshold, largest maxDRAC logged)

A run without any conflict thus reports the thresholds themselves (5 s, 3 s, 1 m/s², see
:class:`~sumo_avoid.sumo.ssm_device.SsmParams`), and a criterion such as ``min_ttc_s >= 1.5`` holds. All
are None when the device did not run (arena scenarios). A TTC of 0 is a collision SUMO saw.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import Metric
from sumo_avoid.rollout.result import RunResult


def ssm_summary(conflicts, params) -> dict:
    """The four ``metrics.json`` keys from a conflict table (:func:`sumo_avoid.sumo.ssm_device.read_conflicts`)
    and the :class:`~sumo_avoid.sumo.ssm_device.SsmParams` SUMO ran with (None: the device was off)."""
    if params is None or conflicts is None:
        return {"min_ttc_s": None, "max_drac_mps2": None, "min_pet_s": None, "ssm_conflicts": None}

    def extreme(col, fn, clamp):
        v = conflicts[col].to_numpy(float)
        v = v[np.isfinite(v)]
        return float(fn(np.append(v, clamp)))

    return {"min_ttc_s": extreme("ttc_s", np.min, params.ttc_threshold_s),
            "max_drac_mps2": extreme("drac_mps2", np.max, params.drac_threshold_mps2),
            "min_pet_s": extreme("pet_s", np.min, params.pet_threshold_s),
            "ssm_conflicts": len(conflicts)}


class SurrogateSafety(Metric):
    """min_ttc_s, max_drac_mps2, min_pet_s (clamped at the device's thresholds), ssm_conflicts."""

    keys = Keys(("min_ttc_s", "max_drac_mps2", "min_pet_s", "ssm_conflicts"))

    def compute(self, run: RunResult) -> dict:
        return ssm_summary(run.tables.get("ssm_conflicts"), run.ssm)
