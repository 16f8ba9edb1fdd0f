"""Layers between controller and actuator (:class:`sumo_avoid.core.interfaces.Layer`), by name:
``ego.rules`` from RULES (``traffic``: signals and the road's speed, on by default) runs first,
then ``ego.safety`` from LAYERS (``danger_time``: seed 004's radar danger-time braking).
``none`` = no layer."""
from sumo_avoid.core.registry import Registry
from sumo_avoid.safety.danger_time import DangerTimeLayer, DangerTimeParams
from sumo_avoid.safety.traffic import RulesParams, TrafficRulesLayer

LAYERS = Registry("layer")
LAYERS.register("danger_time", DangerTimeLayer, DangerTimeParams)

RULES = Registry("rules layer")
RULES.register("traffic", TrafficRulesLayer, RulesParams)
