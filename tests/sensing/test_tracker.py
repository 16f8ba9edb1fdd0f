"""The radar memory (``sensing/tracker.py``) for standing returns, on hand-built scans: one ego, a 90 deg
front radar of 100 m, standing at or driving along +x. No SUMO."""
from __future__ import annotations

import math

import numpy as np

from sumo_avoid.core.types import Detections
from sumo_avoid.sensing.tracker import Tracker


def scan(t, sensor_x, points, vr=None):
    """A scan at time ``t`` from a radar at (sensor_x, 0) looking along +x with returns at ``points``."""
    p = np.asarray(points, float).reshape(-1, 2) - [sensor_x, 0.0]
    r, az = np.hypot(p[:, 0], p[:, 1]), np.arctan2(p[:, 1], p[:, 0])
    vr = np.zeros(len(p)) if vr is None else np.asarray(vr, float)
    return Detections(t, ("ego",), np.array([[sensor_x, 0.0]]), np.zeros(1), np.zeros((1, 2)),
                      np.zeros(len(p), int), r, az, vr)


def test_a_standing_return_out_of_view_is_kept_beside_a_new_return_of_the_part_still_in_view():
    """t=0: a return at (3, 2.5) (40 deg, in view). t=0.1: the radar at x=2 sees (3, 2.5) at 68 deg (out of
    view) and a new return at (5, 2.5) (40 deg), 2 m from it, within the 3 m gate. Standing: both are
    reported. Moving at 5 m/s along +x (radial speed 5 cos 40 deg): the remembered one is replaced."""
    for vr, rows in ((0.0, 2), (-5.0 * 3 / math.hypot(3, 2.5), 1)):
        tr = Tracker(8.0, 90.0, 100.0)
        tr.update(scan(0.0, 0.0, [[3.0, 2.5]], [vr]))
        out = tr.update(scan(0.1, 2.0, [[5.0, 2.5]], [vr]))
        assert out.n == rows


def test_standing_returns_seen_again_at_the_beams_edge_are_one_and_remembered_from_the_last_sighting():
    """Returns of one standing object at the beam's edge (46-47 deg, each out of view at the next scan) at
    t = 0, 0.1, 0.2, 0.04-0.07 m apart: one remembered return, not three; with a 1 s memory it is still
    there at t = 1.1 (1.1 s after the first sighting, 0.9 s after the last) and gone at t = 1.3."""
    tr = Tracker(1.0, 90.0, 100.0)
    for t, p in ((0.0, [3.0, 3.2]), (0.1, [3.05, 3.15]), (0.2, [3.0, 3.25])):
        tr.update(scan(t, 0.0, [p]))
    assert tr.update(scan(0.3, 0.0, [])).n == 1
    assert tr.update(scan(1.1, 0.0, [])).n == 1
    assert tr.update(scan(1.3, 0.0, [])).n == 0
