"""Watching a run from its folder: the recording read back (recording.py), its events (events.py), the
road as drawable data (road_data.py), the self-contained HTML viewer (viewer.py + viewer_js.py), a video
rendered headless (video.py) and the replay in sumo-gui (gui_replay.py)."""
