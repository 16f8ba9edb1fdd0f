"""``sumo``: SUMO's own driver as the baseline. The ego stays an ordinary SUMO vehicle.

Its vehicle type's car-following, lane-changing and junction models drive it, with SUMO's right of
way, signals and safety checks (the speed and lane-change modes SUMO starts it with); the plug-in
never moves it. It is still an ego: taken over when it departs (recorded, given its route and goal),
retired at its goal, and scored with every metric exactly as a driven ego is (footprint and SUMO's
collisions, rule violations, road use, comfort, time to goal), so a study gets a "SUMO's driver" row
and ``travel_time_ratio`` (:mod:`sumo_avoid.studies.baseline`) its denominator.

It declares ``Needs(drives=False)``: the ego book hands no ego to the sensor, controller, layers
or actuator (:meth:`~sumo_avoid.rollout.egos.EgoBook.driven`), and no layer is built for it
(:func:`~sumo_avoid.rollout.assemble.layer_plan`). What it is not: a perfect driver (SUMO's models
with the vType's parameters: Krauss with its ``sigma`` dawdling unless the route file says
otherwise, the sublane model at ``sim.lateral_resolution_m``), nor one that sees what a radar sees
(SUMO knows every vehicle). SUMO's collision check is the scenario's (``sim.sumo_collisions``:
physical contact reported, not acted on, no teleporting).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.control.base_controller import BaseController
from sumo_avoid.core.types import Needs, Observation


@dataclass(frozen=True)
class SumoDriverParams:
    """No parameters: the ego's vType in the route files parameterises SUMO's models."""


class SumoDriverController(BaseController):
    """SUMO's own driver (baseline): the ego stays an ordinary SUMO vehicle, recorded and scored."""

    needs = Needs(drives=False)

    def act(self, obs: Observation) -> np.ndarray:
        raise RuntimeError("controller 'sumo' never acts: SUMO drives its egos (Needs(drives=False))")
