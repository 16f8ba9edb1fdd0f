"""The potential-field controllers: ``apf`` (:mod:`.apf`) and ``apf_sa`` (:mod:`.apf_sa`, APF's
field plus a simulated-annealing escape, composed of an :class:`~.apf.ApfDriver`)."""
from sumo_avoid.control.apf.apf import ApfController, ApfDriver, ApfParams
from sumo_avoid.control.apf.apf_sa import ApfSaController, ApfSaParams

__all__ = ["ApfController", "ApfDriver", "ApfParams", "ApfSaController", "ApfSaParams"]
