"""Grade separation from the net's topology: road users on two parts of the net that cross without a junction are on
two levels (a bridge, a tunnel), whatever their z.

SUMO's nets meet only at junctions: where two edges' lanes cross without sharing a node, SUMO has no right of way
and no collision check between them, and its vehicles drive through each other; in the world one road passes over
the other. The z SUMO gives them (:mod:`sumo_avoid.core.levels`) says so only where the net was built with good
heights: netconvert's ``--osm.layer-elevation`` interpolates a bridge's height along the connected ways, so the road
under a bridge often rises with it (unseen Sao Paulo: the trunk 0.66 m below the ``Viaduto Condessa de Sao Joaquim``
where it passes under, and every one of the net's 657 such lane crossings within 4 m in z; Seoul 951 of 951; nets
built without that option are flat). Counted on one level, a car passing under the ego's bridge stopped the ego
and struck it twice in the metrics.

A part of the net is a normal edge (all its lanes, sidewalks too; it touches its two end nodes) or a junction (its
internal lanes, crossings and walking areas). Two edges are *apart* when their lanes cross and they share no
junction. Junctions are never apart from anything: a junction's shape may reach over the lanes of a road beside it
that SUMO joined to another junction, and counting those as apart would hide real conflicts (so a car inside a
junction under a bridge still counts as on the bridge's level: the heights decide there, as before). :func:`apart_parts` builds the table once per net (:attr:`sumo_avoid.road.network.Road.apart`);
:mod:`sumo_avoid.core.levels` applies it to road users by their lanes (``part_of``, ``apart_mask``, ``apart_pairs``).
"""
from __future__ import annotations

from collections.abc import Mapping

import shapely
from shapely.strtree import STRtree


def apart_parts(net) -> Mapping[str, frozenset[str]]:
    """Edge id -> the edges whose lanes cross its own without a junction (module doc), for a sumolib ``net``; both
    ways (a junction is never apart from anything)."""
    geoms, parts, nodes = [], [], []
    for e in net.getEdges(withInternal=False):
        shapes = [ln.getShape() for ln in e.getLanes()]
        geoms.append(shapely.MultiLineString([[(float(x), float(y)) for x, y, *_ in s] for s in shapes if len(s) >= 2]))
        parts.append(e.getID())
        nodes.append({e.getFromNode().getID(), e.getToNode().getID()})
    if not geoms:
        return {}
    tree = STRtree(geoms)
    a, b = tree.query(geoms, predicate="intersects")
    out: dict[str, set[str]] = {}
    for i, j in zip(a.tolist(), b.tolist()):
        if i < j and not (nodes[i] & nodes[j]) and geoms[i].crosses(geoms[j]):
            out.setdefault(parts[i], set()).add(parts[j])
            out.setdefault(parts[j], set()).add(parts[i])
    return {k: frozenset(v) for k, v in out.items()}
