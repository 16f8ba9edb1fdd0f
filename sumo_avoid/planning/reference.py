"""The shortest collision-free path on the full map: a visibility-graph reference for the planner.

The planner sees only what its radar reveals; this reference sees every obstacle from the start.
Obstacles (convex polygons) are grown by ``inflate_m`` (a mitred offset: still convex polygons,
their vertices pushed out along the corner bisectors); the shortest path of a point among
polygons runs straight between the start, the goal and polygon vertices, so it is the shortest
path in the graph of those points joined wherever the segment between them does not enter a
grown obstacle (shapely) (Dijkstra, scipy). Used by the tests and the planner study to compare
driven path lengths with the best possible.
"""
from __future__ import annotations

import numpy as np
import shapely
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra
from shapely.geometry import LineString, Polygon


def shortest_path(start, goal, obstacles, inflate_m: float) -> tuple[float, np.ndarray]:
    """(length m, (k, 2) vertices) of the shortest path from ``start`` to ``goal`` that keeps
    ``inflate_m`` from every obstacle polygon; (inf, empty) if there is none."""
    grown = [Polygon(np.asarray(o, float)).buffer(inflate_m, join_style="mitre", mitre_limit=10.0) for o in obstacles]
    inner = [g.buffer(-1e-6) for g in grown]  # touching a grown obstacle's boundary is allowed
    corners = [np.asarray(g.exterior.coords)[:-1] for g in grown]
    nodes = np.vstack([np.asarray(start, float)[None], np.asarray(goal, float)[None], *corners])
    free = ~np.array([any(shapely.within(shapely.points(p), g) for g in inner) for p in nodes])
    n = len(nodes)
    i, j = np.triu_indices(n, 1)
    segs = shapely.linestrings(np.stack([nodes[i], nodes[j]], axis=1))
    ok = free[i] & free[j]
    for g in inner:
        ok &= ~shapely.intersects(segs, g)
    w = np.hypot(*(nodes[i] - nodes[j]).T)
    graph = csr_matrix((np.concatenate([w[ok], w[ok]]), (np.concatenate([i[ok], j[ok]]), np.concatenate([j[ok], i[ok]]))),
                       shape=(n, n))
    dist, pred = dijkstra(graph, indices=0, return_predecessors=True)
    if not np.isfinite(dist[1]):
        return float("inf"), np.zeros((0, 2))
    path = [1]
    while path[-1] != 0:
        path.append(int(pred[path[-1]]))
    return float(dist[1]), nodes[path[::-1]]


def crosses(path, obstacles) -> bool:
    """True if the polyline ``path`` enters any obstacle polygon's interior."""
    line = LineString(np.asarray(path, float))
    return any(line.intersects(Polygon(np.asarray(o, float)).buffer(-1e-6)) for o in obstacles)
