"""Hand-computed checks for sumo_avoid.core.geometry (all lengths in m, angles in rad)."""
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from sumo_avoid.core.geometry import (
    box_gap,
    convex_distance,
    convex_overlap,
    footprint_corners,
    near_any,
    pairwise_footprint_distance,
    point_segment_distance,
)

S2 = math.sqrt(2.0)


def box(cx, cy, length=4.0, width=2.0, heading=0.0):
    return footprint_corners([[cx, cy]], [heading], [length], [width])[0]


def shoelace(poly):
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


# ------------------------------------------------------------------ corners
def test_corners_axis_aligned():
    # centre (1,2), L=4, W=2, heading 0: half length 2 along +x, half width 1 along +y
    # FR = (1+2, 2-1), FL = (1+2, 2+1), RL = (1-2, 2+1), RR = (1-2, 2-1)
    c = footprint_corners([[1.0, 2.0]], [0.0], [4.0], [2.0])
    assert c.shape == (1, 4, 2)
    np.testing.assert_allclose(c[0], [[3, 1], [3, 3], [-1, 3], [-1, 1]], atol=1e-12)
    assert shoelace(c[0]) == pytest.approx(8.0)  # CCW -> positive area L*W = 8


def test_corners_rotated_90_and_45():
    # heading pi/2: fwd=(0,1), left=(-1,0); FR = 2*fwd - 1*left = (1,2), FL = (-1,2),
    # RL = -2*fwd + left = (-1,-2), RR = (1,-2)
    c = footprint_corners([[0.0, 0.0], [0.0, 0.0]], [math.pi / 2, math.pi / 4], [4.0, S2], [2.0, S2])
    np.testing.assert_allclose(c[0], [[1, 2], [-1, 2], [-1, -2], [1, -2]], atol=1e-12)
    # sqrt2 x sqrt2 square at 45 deg: fwd=(s,s), left=(-s,s), s=sqrt2/2, half sides s:
    # FR = s*fwd - s*left = (0.5,0.5)-(-0.5,0.5) = (1,0); FL = (0,1); RL = (-1,0); RR = (0,-1)
    np.testing.assert_allclose(c[1], [[1, 0], [0, 1], [-1, 0], [0, -1]], atol=1e-12)
    assert shoelace(c[1]) == pytest.approx(2.0)


# ------------------------------------------------------------------ overlap
def test_overlap_axis_aligned_boxes():
    a = box(0, 0, 2, 2)  # [-1,1]^2
    P = np.stack([a, a, a])
    # centres 1.5 apart: overlap 0.5; 2 apart: touching (counts); 3 apart: gap 1
    Q = np.stack([box(1.5, 0, 2, 2), box(2.0, 0, 2, 2), box(3.0, 0, 2, 2)])
    np.testing.assert_array_equal(convex_overlap(P, Q), [True, True, False])


def test_overlap_rotated_bounding_boxes_overlap_but_shapes_do_not():
    d = box(0, 0, S2, S2, math.pi / 4)  # diamond |x|+|y| <= 1, bbox [-1,1]^2
    # square [0.6,1.6]^2: bbox overlaps, nearest corner (0.6,0.6) has |x|+|y| = 1.2 > 1 -> apart
    # square [0.4,1.4]^2: corner (0.4,0.4) has |x|+|y| = 0.8 < 1 -> overlap
    # diamond centred (1.5,1.5): bbox [0.5,2.5]^2 overlaps [-1,1]^2 but its near edge is
    #   x+y = 2 (through (0.5,1.5) and (1.5,0.5)), parallel to x+y = 1 -> apart
    Q = np.stack([box(1.1, 1.1, 1, 1), box(0.9, 0.9, 1, 1), box(1.5, 1.5, S2, S2, math.pi / 4)])
    P = np.stack([d, d, d])
    np.testing.assert_array_equal(convex_overlap(P, Q), [False, True, False])
    dist, p, q = convex_distance(P, Q)
    # (0.6,0.6) to the line x+y=1: (1.2-1)/sqrt2; foot of perpendicular (0.5,0.5)
    assert dist[0] == pytest.approx(0.2 / S2)
    np.testing.assert_allclose(p[0], [0.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(q[0], [0.6, 0.6], atol=1e-12)
    assert dist[1] == 0.0
    assert dist[2] == pytest.approx((2 - 1) / S2)  # distance between lines x+y=1 and x+y=2


def test_overlap_degenerate_shapes():
    # collinear but disjoint segments [0,1] and [2,3] on the x axis: edge normals alone would
    # not separate them; point vs point 5 apart; point exactly on a segment
    P = np.array([[[0, 0], [1, 0]], [[0, 0], [0, 0]], [[2, 0], [2, 0]]], float)
    Q = np.array([[[2, 0], [3, 0]], [[3, 4], [3, 4]], [[0, 0], [4, 0]]], float)
    np.testing.assert_array_equal(convex_overlap(P, Q), [False, False, True])
    dist, _, _ = convex_distance(P, Q)
    np.testing.assert_allclose(dist, [1.0, 5.0, 0.0], atol=1e-12)


# ------------------------------------------------------------------ distance
def test_distance_boxes_known_gap():
    a = box(0, 0)  # x in [-2,2], y in [-1,1]
    # B centred (7,0.5): x in [5,9], y in [-0.5,1.5] -> gap 5-2 = 3 along x
    # C centred (7,6): x in [5,9], y in [5,7] -> corner to corner (2,1)-(5,5): hypot(3,4) = 5
    dist, p, q = convex_distance(np.stack([a, a]), np.stack([box(7, 0.5), box(7, 6)]))
    np.testing.assert_allclose(dist, [3.0, 5.0], atol=1e-12)
    assert p[0, 0] == pytest.approx(2.0) and q[0, 0] == pytest.approx(5.0)
    assert p[0, 1] == pytest.approx(q[0, 1]) and -0.5 <= p[0, 1] <= 1.0
    np.testing.assert_allclose(p[1], [2, 1], atol=1e-12)
    np.testing.assert_allclose(q[1], [5, 5], atol=1e-12)
    np.testing.assert_allclose(np.hypot(*(q - p).T), dist, atol=1e-12)


def test_distance_overlapping_gives_common_point():
    # [-1,1]^2 and [0.5,2.5]x[-1,1] overlap on [0.5,1]x[-1,1]; a crossing pair ("plus" shape)
    # has no vertex of either inside the other, so the common point is an edge intersection
    P = np.stack([box(0, 0, 2, 2), box(0, 0, 4, 1)])  # second: x in [-2,2], y in [-0.5,0.5]
    Q = np.stack([box(1.5, 0, 2, 2), box(0, 0, 1, 4)])  # second: x in [-0.5,0.5], y in [-2,2]
    dist, p, q = convex_distance(P, Q)
    np.testing.assert_array_equal(dist, [0.0, 0.0])
    np.testing.assert_array_equal(p, q)
    assert 0.5 - 1e-12 <= p[0, 0] <= 1 + 1e-12 and -1 - 1e-12 <= p[0, 1] <= 1 + 1e-12
    assert np.all(np.abs(p[1]) <= 0.5 + 1e-12)


def test_point_segment_distance():
    # segment (0,0)-(4,0): (2,3) -> foot (2,0), d 3 (middle); (-3,4) -> endpoint (0,0), d 5;
    # (7,4) -> endpoint (4,0), d hypot(3,4) = 5.  Degenerate segment (1,1)-(1,1): point (1,1),
    # (2,3) -> hypot(1,2) = sqrt5; (-3,4) -> hypot(4,3) = 5; (7,4) -> hypot(6,3) = sqrt45
    p = [[2, 3], [-3, 4], [7, 4]]
    a = [[0, 0], [1, 1]]
    b = [[4, 0], [1, 1]]
    d, c = point_segment_distance(p, a, b)
    assert d.shape == (3, 2) and c.shape == (3, 2, 2)
    np.testing.assert_allclose(d[:, 0], [3, 5, 5])
    np.testing.assert_allclose(c[:, 0], [[2, 0], [0, 0], [4, 0]])
    np.testing.assert_allclose(d[:, 1], [math.sqrt(5), 5, math.sqrt(45)])
    np.testing.assert_allclose(c[:, 1], [[1, 1]] * 3)


def test_segment_vs_rectangle():
    r = box(0, 0)  # x in [-2,2], y in [-1,1]
    segs = np.array([[[0, 3], [4, 3]],  # above: y=3 vs top edge y=1 -> 2
                     [[3, 0], [5, 0]],  # right of it: x=3 vs x=2 -> 1
                     [[-3, 0], [3, 0]]], float)  # straight through -> 0
    R = np.stack([r, r, r])
    np.testing.assert_array_equal(convex_overlap(segs, R), [False, False, True])
    dist, p, q = convex_distance(segs, R)
    np.testing.assert_allclose(dist, [2.0, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(p[1], [3, 0], atol=1e-12)
    np.testing.assert_allclose(q[1], [2, 0], atol=1e-12)
    assert p[2, 1] == pytest.approx(0.0) and abs(p[2, 0]) <= 2 + 1e-12


def test_pairwise_footprint_distance():
    A = np.stack([box(0, 0), box(0, 10), box(7, 1)])
    B = np.stack([box(7, 0.5), box(0, 0)])
    d = pairwise_footprint_distance(A, B)
    # (0,10) box: x in [-2,2], y in [9,11]; vs (7,0.5): dx = 5-2 = 3, dy = 9-1.5 = 7.5
    #   -> sqrt(9 + 56.25) = sqrt(65.25);  vs (0,0): dy = 9-1 = 8
    # (7,1) box overlaps (7,0.5) -> 0; vs (0,0): gap 5-2 = 3
    np.testing.assert_allclose(d, [[3.0, 0.0], [math.sqrt(65.25), 8.0], [0.0, 3.0]], atol=1e-12)
    assert pairwise_footprint_distance(A[:0], B).shape == (0, 2)


def test_random_cross_check_against_shapely():
    # not hand-computed: an independent reference (shapely/GEOS) on random rectangles/segments
    shapely = pytest.importorskip("shapely")
    rng = np.random.default_rng(1)
    M = 2000
    A = footprint_corners(rng.uniform(-5, 5, (M, 2)), rng.uniform(-3, 3, M),
                          rng.uniform(1, 6, M), rng.uniform(0.5, 3, M))
    B = footprint_corners(rng.uniform(-5, 5, (M, 2)), rng.uniform(-3, 3, M),
                          rng.uniform(1, 6, M), rng.uniform(0.5, 3, M))
    S = rng.uniform(-5, 5, (M, 2, 2))
    for P, gP in ((A, shapely.polygons(A)), (S, shapely.linestrings(S))):
        gB = shapely.polygons(B)
        d, p, q = convex_distance(P, B)
        ref = shapely.distance(gP, gB)
        np.testing.assert_allclose(d, ref, atol=1e-9)
        np.testing.assert_array_equal(convex_overlap(P, B), ref == 0)
        assert shapely.distance(gP, shapely.points(p)).max() < 1e-9
        assert shapely.distance(gB, shapely.points(q)).max() < 1e-9


def test_near_any_hand_values():
    centres = np.array([[0.0, 0.0], [100.0, 0.0]])
    points = np.array([[3.0, 4.0], [5.0, 0.0001], [50.0, 0.0], [103.0, -4.0], [0.0, 5.0]])
    # distances to the nearer centre: 5, 5.000000001, 50, 5, 5
    assert near_any(points, centres, 5.0).tolist() == [True, False, False, True, True]
    assert near_any(points, centres, 50.0).tolist() == [True, True, True, True, True]
    assert near_any(points, centres[:0], 5.0).tolist() == [False] * 5


def test_near_any_equals_the_kdtree_answer():
    """The sweep settles most points; the rest go to the k-d tree: together the k-d tree's answer,
    on random layouts (points far from every centre along the sweep axis included) and a road along y."""
    rng = np.random.default_rng(3)
    for k in range(300):
        n, m = int(rng.integers(1, 300)), int(rng.integers(1, 40))
        scale = rng.uniform(1, 1000, 2)
        p, c = rng.uniform(0, 1, (n, 2)) * scale, rng.uniform(0, 1, (m, 2)) * scale
        r = float(rng.uniform(0, 300))
        ref = cKDTree(c).query(p, k=1, distance_upper_bound=r * (1 + 1e-9))[0] <= r
        assert np.array_equal(near_any(p, c, r), ref), k


def test_box_gap_hand_values():
    # a beside b across (d): 1 m apart, pointing from b to a along +d; diagonal 3-4-5; overlapping: 0
    lo_a = np.array([[0.0, 0.0], [10.0, 5.0], [0.0, 0.0]])
    hi_a = np.array([[4.0, 2.0], [12.0, 6.0], [4.0, 2.0]])
    lo_b = np.array([[1.0, -2.0], [0.0, 0.0], [3.0, 1.0]])
    hi_b = np.array([[3.0, -1.0], [7.0, 1.0], [5.0, 3.0]])
    gap, to_a = box_gap(lo_a, hi_a, lo_b, hi_b)
    np.testing.assert_allclose(gap, [1.0, 5.0, 0.0])
    np.testing.assert_allclose(to_a, [[0.0, 1.0], [0.6, 0.8], [0.0, 0.0]])
