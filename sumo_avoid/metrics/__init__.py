"""Metrics of a finished run, by name (``output.metrics``; default: :data:`STANDARD` plus the
controller's own). Each is a :class:`~sumo_avoid.metrics.base.Metric`; later ones win on a shared key."""
from sumo_avoid.core.registry import Registry
from sumo_avoid.core.types import Keys
from sumo_avoid.metrics.base import clean
from sumo_avoid.metrics.comfort import Comfort
from sumo_avoid.metrics.crossing_use import CrossingViolations
from sumo_avoid.metrics.flock_score import FlockingOrder
from sumo_avoid.metrics.formation_score import FormationScore
from sumo_avoid.metrics.road_use import RoadUse
from sumo_avoid.metrics.rules import RuleViolations
from sumo_avoid.metrics.ssm import SurrogateSafety
from sumo_avoid.metrics.standard import (
    Collisions,
    MinGap,
    Motion,
    PhiColl,
    PhiWall,
    PluginStats,
    RunInfo,
    VulnerableRoadUsers,
)
from sumo_avoid.metrics.ttc import MinTTC2D

METRICS = Registry("metric")
METRICS.register("run", RunInfo)
METRICS.register("collisions", Collisions)
METRICS.register("min_gap", MinGap)
METRICS.register("vru", VulnerableRoadUsers)
METRICS.register("phi_coll", PhiColl)
METRICS.register("phi_wall", PhiWall)
METRICS.register("plugin_stats", PluginStats)
METRICS.register("motion", Motion)
METRICS.register("flocking", FlockingOrder)
METRICS.register("formation", FormationScore)
METRICS.register("rules", RuleViolations)
METRICS.register("crossings", CrossingViolations)
METRICS.register("road_use", RoadUse)
METRICS.register("comfort", Comfort)
METRICS.register("ssm", SurrogateSafety)
METRICS.register("ttc2d", MinTTC2D)

# ttc2d last: its pair search is the widest, and the shared search keeps the widest one
STANDARD = ("run", "collisions", "vru", "min_gap", "phi_coll", "phi_wall", "plugin_stats", "motion", "rules", "crossings",
            "road_use", "comfort", "ssm", "ttc2d")


def compute(run, names=STANDARD) -> dict:
    """``metrics.json`` of a run: the named metrics in order, JSON-ready."""
    out: dict = {}
    for name in names:
        out.update(METRICS[name].factory().compute(run))
    return clean(out)


def declared_keys(names, scn, stats: Keys) -> Keys:
    """The keys the named metrics declare for a run of ``scn`` whose plug-ins' counters are ``stats``."""
    out = Keys()
    for name in names:
        out = out | METRICS[name].factory.keys_for(scn, stats)
    return out
