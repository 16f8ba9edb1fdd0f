"""The ``flocking`` controller (SPEC §1): its terms (:mod:`.terms`), in the plane or an arena
(:mod:`.flocking`) and on roads, each ego in its route frame (:mod:`.road_flock`)."""
from sumo_avoid.control.flocking.flocking import FlockingController
from sumo_avoid.control.flocking.terms import FlockingParams

__all__ = ["FlockingController", "FlockingParams"]
