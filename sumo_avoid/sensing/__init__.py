"""What the controllers see, by name (``ego.sensor``): ``truth`` or ``radar`` (parameters in
``[sensors.radar]``), each a :class:`sumo_avoid.core.interfaces.Sensor` (sensors.py). The radar
emulator (radar.py, its compiled parts in occlusion.py), its memory (tracker.py), returns -> obstacle
boxes (perception.py), the detection log (log.py), V2V for flocks (v2v.py)."""
from sumo_avoid.core.registry import Registry
from sumo_avoid.sensing.radar import RadarParams
from sumo_avoid.sensing.sensors import RadarSensor, TruthSensor

SENSORS = Registry("sensor")
SENSORS.register("truth", TruthSensor)
SENSORS.register("radar", RadarSensor, RadarParams)
