"""What the controllers see, by name (``ego.sensor``): ``truth`` or ``radar``
(:class:`sumo_avoid.core.interfaces.Sensor`). The radar emulator (radar.py, its compiled parts in
occlusion.py), its memory (tracker.py), returns -> obstacle boxes (perception.py), the detection
log (log.py), V2V for flocks (v2v.py)."""
from sumo_avoid.core.registry import Registry
from sumo_avoid.sensing.radar import Radar, RadarParams
from sumo_avoid.sensing.sensors import RadarSensor, TruthSensor
from sumo_avoid.sensing.v2v import V2VLink

_STREAM = {"front": 4, "rear": 5, "left": 8, "right": 9}  # each mount's noise stream (ctx.rng)


def _link(v2v, ctx):
    return V2VLink(v2v, ctx.rng()) if v2v is not None else None


def truth(params: RadarParams, ctx, *, needs_scans: bool = False, v2v=None) -> TruthSensor:
    """Ground truth (a front radar only for layers that need scans)."""
    radar = Radar(params, ctx.rng(4)) if needs_scans else None
    return TruthSensor(radar, ctx.obstacles, _link(v2v, ctx))


def radar(params: RadarParams, ctx, *, needs_scans: bool = True, v2v=None) -> RadarSensor:
    """Front radar (+ rear with radar.rear, + left and right with radar.side), one tracker memory."""
    return RadarSensor(tuple(Radar(params, ctx.rng(_STREAM[m]), mount=m) for m in params.mounts()),
                       ctx.obstacles, _link(v2v, ctx))


SENSORS = Registry("sensor")
SENSORS.register("truth", truth, RadarParams)
SENSORS.register("radar", radar, RadarParams)
