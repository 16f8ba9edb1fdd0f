"""road/elements.py on nets SUMO's own tools build: lane permissions, crossings, walking areas, z."""
from __future__ import annotations

import pathlib
import subprocess

import numpy as np
import pytest
import sumo

from sumo_avoid.road.network import Road

BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"


@pytest.fixture(scope="module")
def walkable(tmp_path_factory) -> Road:
    """A netgenerate 2x2 grid (80 m) with sidewalks and crossings guessed, a light at every junction."""
    out = tmp_path_factory.mktemp("walk") / "g.net.xml"
    subprocess.run([str(BIN / "netgenerate"), "--grid", "--grid.number", "2", "--grid.length", "80",
                    "--sidewalks.guess", "--crossings.guess", "--tls.guess", "--seed", "1", "-o", str(out)],
                   check=True, capture_output=True)
    return Road(__import__("sumolib").net.readNet(str(out), withInternal=True), str(out))


def test_sidewalks_admit_only_pedestrians_and_roads_not_pedestrians(walkable):
    el = walkable.elements
    normal = [ln for ln in el.lanes.values() if ln.function == ""]
    sidewalks = [ln for ln in normal if ln.allow == {"pedestrian"}]
    roads = [ln for ln in normal if ln.allows("passenger")]
    # netgenerate's grid: 4 two-way edges, each direction a sidewalk (lane 0) and a road lane (lane 1)
    assert len(sidewalks) == len(roads) == 8
    assert all(ln.index == 0 for ln in sidewalks) and all(ln.index == 1 for ln in roads)
    assert not any(ln.allows("pedestrian") for ln in roads)
    assert set(el.lanes_allowing("passenger", functions=("",))) == {ln.id for ln in roads}


def test_crossings_and_walking_areas_are_read(walkable):
    el = walkable.elements
    assert len(el.crossings) == 4 and len(el.walking_areas) == 8
    for c in el.crossings.values():
        assert c.junction in el.junctions
        assert c.lane in el.lanes and el.lanes[c.lane].function == "crossing"
        assert el.lanes[c.lane].allow == {"pedestrian"}
        assert c.crossed_edges and all(e in {ln.edge for ln in el.lanes.values()} for e in c.crossed_edges)
        assert c.shape.shape[1] == 2 and len(c.shape) >= 2


def test_lane_shapes_carry_z_and_records_are_read_only(walkable):
    ln = next(iter(walkable.elements.lanes.values()))
    assert ln.shape.shape[1] == 3 and np.all(ln.shape[:, 2] == 0.0)  # a flat net
    with pytest.raises(ValueError):
        ln.shape[0, 0] = 1.0
    with pytest.raises(TypeError):
        walkable.elements.lanes["x"] = ln  # type: ignore[index]
