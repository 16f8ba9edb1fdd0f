"""watch.events: a contact's label names the ego (whichever of the pair it is), the other party, and how it happened."""
from types import SimpleNamespace

import pandas as pd

from sumo_avoid.watch.events import events


def test_a_contact_names_the_ego_the_other_and_how():
    contact = {"step": 10, "time_s": 1.0, "a": "bike20", "b": "car46", "x": 1.0, "y": 2.0, "ego": "car46",
               "kind": "ego_stopped", "impact_speed_mps": 5.13, "other_jumped": False}
    jumped = dict(contact, time_s=2.0, a="car46", b="ped258", kind="lateral", impact_speed_mps=0.26, other_jumped=True)
    old = {"step": 30, "time_s": 3.0, "a": "ego", "b": "car1", "x": 0.0, "y": 0.0}  # a run recorded before the kinds
    rec = SimpleNamespace(metrics={"collision_events": [contact, jumped, old]}, traj=pd.DataFrame(), egos=["car46"], ssm=None)
    got = events(rec)
    assert [(e.ego, e.other) for e in got] == [("car46", "bike20"), ("car46", "ped258"), ("ego", "car1")]
    assert got[0].label == "1.0 s collision (ego stopped, 5.1 m/s): car46 with bike20"
    assert got[1].label == "2.0 s collision (lateral, 0.3 m/s, it jumped): car46 with ped258"
    assert got[2].label == "3.0 s collision: ego with car1"
