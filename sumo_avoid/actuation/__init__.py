"""Actuators by name (``ego.actuator``, default ``kinematic``; parameters in ``[actuators.NAME]``):
desired 2-D velocity -> motion within the vehicle's limits (:class:`sumo_avoid.core.interfaces.Actuator`)."""
from sumo_avoid.actuation.kinematic import KinematicActuator, KinematicParams
from sumo_avoid.actuation.relaxation import RelaxationActuator, RelaxationParams
from sumo_avoid.core.registry import Registry

ACTUATORS = Registry("actuator")
ACTUATORS.register("kinematic", KinematicActuator, KinematicParams)
ACTUATORS.register("relaxation", RelaxationActuator, RelaxationParams)
