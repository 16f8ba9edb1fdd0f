"""sumo_avoid: obstacle-avoidance controllers driven inside Eclipse SUMO, with safety metrics.

Data flows one way each step: snapshot -> sensor -> controller -> actuator -> recorder.
Only :mod:`sumo_avoid.sumo.sim` talks to libsumo.
"""

__version__ = "0.1.0"
