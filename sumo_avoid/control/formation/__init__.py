"""The ``formation`` controller (SPEC §3): the controller (:mod:`.formation`), its field maths
(:mod:`.field`), what its members know (:mod:`.obstacle_lists`), the leader's path (:mod:`.trail`),
the safety shield (:mod:`.shield`), and on a road lane by lane (:mod:`.lane_plan`) or in the
leader's route frame (:mod:`.road_frame`). The shapes are :mod:`sumo_avoid.planning.formation_shape`."""
from sumo_avoid.control.formation.formation import FormationController, FormationParams

__all__ = ["FormationController", "FormationParams"]
