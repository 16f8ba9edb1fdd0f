"""The ``ga_planner`` controller: a genetic-algorithm path planner on a radar map, tracked by pure
pursuit (:mod:`.ga_planner`; the planning itself is :mod:`sumo_avoid.planning`)."""
from sumo_avoid.control.ga_planner.ga_planner import GaPlannerController, GaPlannerParams

__all__ = ["GaPlannerController", "GaPlannerParams"]
