"""Layers between controller and actuator (:class:`sumo_avoid.core.interfaces.Layer`), by name
(``ego.safety``): ``danger_time`` (seed 004's radar danger-time braking). ``none`` = no layer."""
from sumo_avoid.core.registry import Registry
from sumo_avoid.safety.danger_time import DangerTimeLayer, DangerTimeParams

LAYERS = Registry("layer")
LAYERS.register("danger_time", DangerTimeLayer, DangerTimeParams)
