"""Controllers by name (``ego.controller``): ``CONTROLLERS[name]`` -> (class, frozen parameters).

Every controller is built as ``cls(params, context)`` (:class:`sumo_avoid.core.interfaces.Context`)
and follows :class:`sumo_avoid.core.interfaces.Controller`. A new controller is one file here plus
one line below (docs/writing_a_controller.md).
"""
from sumo_avoid.control.apf.apf import ApfController, ApfParams
from sumo_avoid.control.apf.apf_sa import ApfSaController, ApfSaParams
from sumo_avoid.control.flocking.terms import FlockingParams
from sumo_avoid.control.flocking.flocking import FlockingController
from sumo_avoid.control.formation.formation import FormationController, FormationParams
from sumo_avoid.control.ga_planner.ga_planner import GaPlannerController, GaPlannerParams
from sumo_avoid.control.scripted import ScriptedController, ScriptedParams
from sumo_avoid.core.registry import Registry

CONTROLLERS = Registry("controller")
CONTROLLERS.register("apf", ApfController, ApfParams)
CONTROLLERS.register("apf_sa", ApfSaController, ApfSaParams)
CONTROLLERS.register("flocking", FlockingController, FlockingParams)
CONTROLLERS.register("formation", FormationController, FormationParams)
CONTROLLERS.register("ga_planner", GaPlannerController, GaPlannerParams)
CONTROLLERS.register("scripted", ScriptedController, ScriptedParams)
