"""Where a radar return counts as a person at the kerb (Road.at_kerb): the walkways, and the ends of the
crossings where SUMO stands the people who wait to cross -- across the crossing's whole width, which on a
real corner reaches past the walking area onto the lane beside it."""
from __future__ import annotations

import pathlib

import numpy as np
import pytest

from sumo_avoid.road.network import KERB_CAP_M, Road

ROOT = pathlib.Path(__file__).parents[2]
BOLOGNA = ROOT.parent / "shared" / "cities" / "bologna_acosta" / "acosta_peds.net.xml"


def test_the_end_of_a_crossing_is_the_kerb_its_middle_is_not():
    road = Road.from_net_file(ROOT / "scenarios" / "streets" / "signal_crossing.net.xml")
    for c in road.elements.crossings.values():
        shape = np.asarray(c.shape, float)[:, :2]
        end, prev = shape[-1], shape[-2]
        axis = (end - prev) / np.hypot(*(end - prev))
        across = np.array([-axis[1], axis[0]])
        middle = 0.5 * (shape[0] + shape[-1])
        pts = np.array([end + 0.5 * KERB_CAP_M * axis + 0.45 * c.width_m * across,  # waiting, near the far side
                        end - 0.45 * c.width_m * across,  # on its end, the other side
                        middle,  # on the crossing: on the carriageway
                        end - 1.0 * axis])  # 1 m onto the crossing
        assert road.at_kerb(pts).tolist() == [True, True, False, False], c.id
        assert not road.on_walkway(pts[2:]).any()


@pytest.mark.skipif(not BOLOGNA.is_file(), reason="../shared/cities is not beside the checkout")
def test_the_people_waiting_at_bologna_corner_1c_are_at_the_kerb_not_in_the_lane():
    road = Road.from_net_file(BOLOGNA)
    # where SUMO stood four people waiting at crossing :1c_c1's east end (bologna_signals seed 1, 404-440 s):
    # up to 1 m outside walking area :1c_w0; the through lane :1c_1_0 beside them, its centre x 1508.6 there
    people = np.array([[1509.96, 823.68], [1510.11, 823.06], [1510.26, 822.43], [1510.40, 821.81]])
    assert road.on_walkway(people).tolist() == [False, False, False, True]
    assert road.at_kerb(people).all()
    lane_and_crossing = np.array([[1508.63, 822.0], [1505.7, 821.0], [1509.0, 826.0]])
    assert not road.at_kerb(lane_and_crossing).any()
