"""Actuators by name (``actuator.mode``): desired 2-D velocity -> motion within the vehicle's limits
(:class:`sumo_avoid.core.interfaces.Actuator`)."""
from sumo_avoid.actuation.kinematic import KinematicActuator
from sumo_avoid.actuation.params import ActuatorConfig
from sumo_avoid.actuation.relaxation import RelaxationActuator
from sumo_avoid.core.registry import Registry

ACTUATORS = Registry("actuator")
ACTUATORS.register("kinematic", lambda p, ctx: KinematicActuator(p, ctx.step_s), ActuatorConfig)
ACTUATORS.register("relaxation", lambda p, ctx: RelaxationActuator(p, ctx.step_s, ctx.rng(7)), ActuatorConfig)
