"""Controllers by name: ``REGISTRY[name] = (ControllerClass, ParamsDataclass)``.

Every controller takes ``(params, road, rng)`` and follows :class:`.base.Controller`.
"""
from sumo_avoid.control.apf import ApfController, ApfParams
from sumo_avoid.control.apf_sa import ApfSaController, ApfSaParams
from sumo_avoid.control.flocking import FlockingController, FlockingParams
from sumo_avoid.control.scripted import ScriptedController, ScriptedParams

REGISTRY = {
    "apf": (ApfController, ApfParams),
    "apf_sa": (ApfSaController, ApfSaParams),
    "flocking": (FlockingController, FlockingParams),
    "scripted": (ScriptedController, ScriptedParams),
}


def make_controller(name: str, params, road, rng):
    cls, _ = REGISTRY[name]
    return cls(params, road, rng)
