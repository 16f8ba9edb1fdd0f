"""Layers between controller and actuator (:class:`sumo_avoid.core.interfaces.Layer`), by name in
``ego.layers``, applied in that order (default ``["traffic"]``), parameters in ``[layers.NAME]``:
``traffic`` (signals, right of way and the road's speed; :mod:`.traffic`) and ``danger_time``
(seed 004's radar danger-time braking; :mod:`.danger_time`, which also runs as a monitor when not
chosen and the sensor provides scans). ``ego.layers = []``: no layer."""
from sumo_avoid.core.registry import Registry
from sumo_avoid.road.regulation import RulesParams
from sumo_avoid.safety.danger_time import DangerTimeLayer, DangerTimeParams
from sumo_avoid.safety.traffic import TrafficRulesLayer

LAYERS = Registry("layer")
LAYERS.register("danger_time", DangerTimeLayer, DangerTimeParams)
LAYERS.register("traffic", TrafficRulesLayer, RulesParams)
