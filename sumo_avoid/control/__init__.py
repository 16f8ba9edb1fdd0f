"""Controllers by name (``ego.controller``): ``CONTROLLERS[name]`` -> (class, frozen parameters).

Every controller is built as ``cls(params, context)`` (:class:`sumo_avoid.core.interfaces.Context`)
and follows :class:`sumo_avoid.core.interfaces.Controller` (defaults:
:class:`~sumo_avoid.control.base_controller.BaseController`). A family of controllers is a folder
(``apf/``, ``flocking/``, ``formation/``, ``ga_planner/``) whose ``__init__`` exports its controllers and
parameters; a simple controller is one file here (``scripted.py``, ``policy.py``, ``sumo_driver.py``); either
is one line below (docs/writing_a_controller.md). ``sumo`` is SUMO's own driver, the baseline: it declares
``Needs(drives=False)`` and the ego stays SUMO's.
"""
from sumo_avoid.control.apf import ApfController, ApfParams, ApfSaController, ApfSaParams
from sumo_avoid.control.flocking import FlockingController, FlockingParams
from sumo_avoid.control.formation import FormationController, FormationParams
from sumo_avoid.control.ga_planner import GaPlannerController, GaPlannerParams
from sumo_avoid.control.policy import PolicyController, PolicyParams
from sumo_avoid.control.scripted import ScriptedController, ScriptedParams
from sumo_avoid.control.sumo_driver import SumoDriverController, SumoDriverParams
from sumo_avoid.core.registry import Registry

CONTROLLERS = Registry("controller")
CONTROLLERS.register("apf", ApfController, ApfParams)
CONTROLLERS.register("apf_sa", ApfSaController, ApfSaParams)
CONTROLLERS.register("flocking", FlockingController, FlockingParams)
CONTROLLERS.register("formation", FormationController, FormationParams)
CONTROLLERS.register("ga_planner", GaPlannerController, GaPlannerParams)
CONTROLLERS.register("policy", PolicyController, PolicyParams)
CONTROLLERS.register("scripted", ScriptedController, ScriptedParams)
CONTROLLERS.register("sumo", SumoDriverController, SumoDriverParams)
