"""Sensors between the world and the controllers: the radar emulator (radar.py), its short-term
memory (tracker.py), detections -> obstacle boxes (perception.py), the detection log (log.py) and the
truth-vs-radar study (study.py). See docs/radar.md."""
