"""GA planner (SPEC §4): each fitness term and each operator pinned to hand-computed values; the
compiled clearance against its numpy formulation; a whole plan deterministic and usable."""
import math

import numpy as np
import pytest
from conftest import SCENARIOS, cli_in_process

from sumo_avoid.planning import ga


def _paths(*paths):
    return np.array(paths, float)


def clearance_numpy(pop, pts):
    """The numpy broadcast over (N, n-1, P, 2) the kernel replaced."""
    a = pop[:, :-1, None, :]
    ab = pop[:, 1:, None, :] - a
    ap = pts[None, None] - a
    den = (ab * ab).sum(-1)
    t = np.clip((ap * ab).sum(-1) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    gap = ap - t[..., None] * ab
    return np.sqrt((gap * gap).sum(-1).min(axis=(1, 2)))


def test_length_term_is_one_minus_length_over_the_longest():
    pop = _paths([[0, 0], [3, 4], [3, 10]], [[0, 0], [6, 8], [6, 20]])  # L = 5 + 6 = 11 and 10 + 12 = 22
    assert ga.path_lengths(pop) == pytest.approx([11.0, 22.0])
    p = ga.GaParams(w_length=1.0, w_obstacle=0.0, w_smooth=0.0)
    f, _ = ga.fitness(pop, np.zeros((0, 2)), p)
    assert f == pytest.approx([0.5, 0.0])


def test_clearance_of_segments_to_points():
    pop = _paths([[0, 0], [10, 0], [10, 10]])
    assert ga.clearance(pop, [[5, 3]])[0] == pytest.approx(3.0)  # foot of the perpendicular
    assert ga.clearance(pop, [[-3, -4]])[0] == pytest.approx(5.0)  # beyond the first end point
    assert ga.clearance(pop, [[13, 5], [5, 3]])[0] == pytest.approx(3.0)  # nearest of several
    assert ga.clearance(pop, np.zeros((0, 2)))[0] == math.inf


def test_compiled_clearance_equals_the_numpy_formulation():
    rng = np.random.default_rng(3)
    for _ in range(20):
        pop = rng.uniform(0, 100, (int(rng.integers(1, 30)), int(rng.integers(2, 10)), 2))
        pts = rng.uniform(0, 100, (int(rng.integers(1, 300)), 2))
        np.testing.assert_allclose(ga.clearance(pop, pts), clearance_numpy(pop, pts), rtol=0, atol=1e-12)


def test_obstacle_term_at_contact_one_radar_range_and_beyond():
    # 0.01 / (0.01 + exp(-4.6 d / R)): d = 0 -> 0.01 / 1.01; d = R -> 0.01 / (0.01 + e^-4.6) = 0.49871
    assert ga.obstacle_term(0.0, 100.0) == pytest.approx(0.00990099, abs=1e-8)
    assert ga.obstacle_term(100.0, 100.0) == pytest.approx(0.498707, abs=1e-6)
    assert ga.obstacle_term(300.0, 100.0) == pytest.approx(0.99990, abs=1e-5)
    assert ga.obstacle_term(np.inf, 100.0) == 1.0


def test_smooth_term_sums_chord_over_detour_and_divides_by_the_best():
    bent = [[0, 0], [1, 0], [1, 1]]  # one inner waypoint: sqrt(2) / (1 + 1)
    straight = [[0, 0], [1, 0], [2, 0]]  # 2 / (1 + 1) = 1
    assert ga.smooth_raw(_paths(bent, straight)) == pytest.approx([math.sqrt(2) / 2, 1.0])
    p = ga.GaParams(w_length=0.0, w_obstacle=0.0, w_smooth=1.0)
    f, _ = ga.fitness(_paths(bent, straight), np.zeros((0, 2)), p)
    assert f == pytest.approx([math.sqrt(2) / 2, 1.0])


def test_fitness_is_the_weighted_sum():
    pop = _paths([[0, 0], [5, 0], [10, 0]], [[0, 0], [5, 5], [10, 0]])
    pts = np.array([[5.0, -4.0]])
    p = ga.GaParams(w_length=2.0, w_obstacle=3.0, w_smooth=0.5)
    f, c = ga.fitness(pop, pts, p)
    L = np.array([10.0, 2 * math.sqrt(50)])
    S = np.array([1.0, 10 / (2 * math.sqrt(50))])
    # (5,-4): 4 m below the first path; from the second, the foot on its first segment is (0.5, 0.5)
    assert c == pytest.approx([4.0, 4.5 * math.sqrt(2)])
    obst = 0.01 / (0.01 + np.exp(-4.6 * c / 100.0))
    assert f == pytest.approx(2.0 * (1 - L / L.max()) + 3.0 * obst + 0.5 * S / S.max())


def test_crossover_swaps_the_first_c_waypoints():
    a = [[0, 0], [1, 1], [2, 2], [3, 3]]
    b = [[0, 0], [1, -1], [2, -2], [3, 3]]
    c1, c2 = ga.crossover(a, b, 2)
    assert c1.tolist() == [[0, 0], [1, -1], [2, 2], [3, 3]]
    assert c2.tolist() == [[0, 0], [1, 1], [2, -2], [3, 3]]


def test_mutation_moves_inner_waypoints_whose_draw_exceeds_the_threshold():
    pop = _paths([[0, 0], [1, 0], [2, 0], [3, 0]])
    draws = np.array([[0.9, 0.5, 0.8, 0.95]])
    steps = np.full((1, 4, 2), 0.25)
    out = ga.mutate(pop, draws, steps, threshold=0.7)
    assert out.tolist() == [[[0, 0], [1, 0], [2.25, 0.25], [3, 0]]]  # ends fixed, 0.5 <= T_m stays
    assert ga.mutate(pop, draws, steps, threshold=0.8)[0, 2].tolist() == [2.0, 0.0]  # 0.8 does not exceed 0.8


def test_regression_pulls_towards_the_line_only_when_collision_free():
    pop = _paths([[0, 0], [5, 4], [10, 0]])
    out, moved = ga.regress(pop, np.zeros((0, 2)), rate=0.5, safety_radius_m=1.0)
    assert moved.tolist() == [True] and out[0, 1].tolist() == [5.0, 2.0]
    # a point 1.249 m from the original first segment and 0.557 m from the pulled one (hand computed)
    pts = np.array([[2.5, 0.4]])
    assert ga.clearance(pop, pts)[0] == pytest.approx(1.2494, abs=1e-4)
    assert ga.clearance(out, pts)[0] == pytest.approx(0.5571, abs=1e-4)
    kept, moved = ga.regress(pop, pts, rate=0.5, safety_radius_m=1.0)
    assert moved.tolist() == [False] and kept[0, 1].tolist() == [5.0, 4.0]
    _, moved = ga.regress(pop, pts, rate=0.5, safety_radius_m=0.5)  # 0.557 >= 0.5: allowed
    assert moved.tolist() == [True]


def test_smoothing_replaces_sharp_waypoints_by_the_midpoint_in_order():
    sharp = ga.smooth(_paths([[0, 0], [5, 5], [10, 0]]), 1.15)  # (7.07 + 7.07) / 10 = 1.414 > 1.15
    assert sharp[0, 1].tolist() == [5.0, 0.0]
    mild = ga.smooth(_paths([[0, 0], [5, 1], [10, 0]]), 1.15)  # 2 * 5.099 / 10 = 1.0198
    assert mild[0, 1].tolist() == [5.0, 1.0]
    # in order: WP_1 -> (5, 5) (ratio 20 / 14.14), then WP_2 sees the new WP_1: (7.07 + 10) / 7.07 -> (7.5, 2.5)
    box = ga.smooth(_paths([[0, 0], [0, 10], [10, 10], [10, 0]]), 1.15)
    assert box[0].tolist() == [[0, 0], [5, 5], [7.5, 2.5], [10, 0]]


def test_ranking_puts_usable_paths_first_then_the_least_violation():
    f = np.array([0.9, 0.2, 0.5, 0.8])
    v = np.array([0.5, 0.0, 0.0, 0.1])
    assert ga._ranking(f, v).tolist() == [2, 1, 3, 0]


def test_first_segment_needs_only_to_not_get_closer():
    pop = _paths([[0, 0], [0, 10], [20, 10]], [[0, 0], [2, 0], [20, 10]])
    pts = np.array([[1.0, -2.0]])  # the start is 2.24 m from it
    c, v = ga.violation(pop, pts, 3.0, 2.2)
    assert c == pytest.approx([math.sqrt(5), 2.0])
    # path 1: first segment keeps sqrt(5) >= 2.2, the rest 12 m; path 2: first 2.0 (0.2 short),
    # second segment from its start (2, 0): sqrt(5) (3 - sqrt(5) short); the shortfalls add up
    assert v == pytest.approx([0.0, 0.2 + 3.0 - math.sqrt(5)])


def test_violation_adds_the_shortfall_of_every_segment():
    # points 1 m below the middle of two segments of a path along y = 0: each 2 m short of 3 m
    pts = np.array([[5.0, -1.0], [15.0, -1.0]])
    one = _paths([[0, 0], [10, 0], [20, 0]])
    c, v = ga.violation(one, pts[:1], 3.0, 3.0)
    assert c == pytest.approx([1.0]) and v == pytest.approx([2.0])
    c, v = ga.violation(one, pts, 3.0, 3.0)  # the worst segment alike, the sum twice as large
    assert c == pytest.approx([1.0]) and v == pytest.approx([4.0])


def test_free_space_paths_leave_through_free_segments():
    # the start inside a U of points open to the west (-x), the goal east behind its bottom
    u = np.concatenate([np.column_stack([np.arange(-2.0, 9.0), np.full(11, 6.0)]),
                        np.column_stack([np.arange(-2.0, 9.0), np.full(11, -6.0)]),
                        np.column_stack([np.full(13, 8.0), np.arange(-6.0, 7.0)])])
    p = ga.GaParams(free_init_reach_m=20.0)
    pts = ga.sorted_points(u)
    paths = ga.free_space_paths([0.0, 0.0], [40.0, 0.0], 10, 8, pts, p, np.random.default_rng(3), None, 3.0)
    assert len(paths) == 10
    assert paths[:, 0] == pytest.approx(np.zeros((10, 2))) and paths[:, -1] == pytest.approx(np.tile([40.0, 0.0], (10, 1)))
    first, rest = ga.kernels.clearance(np.ascontiguousarray(paths[:, :3]), pts)
    assert (first >= 3.0).all() and (rest >= 3.0).all()  # start -> v1 -> v2 keep the radius
    hop = np.hypot(*(paths[:, 1] - paths[:, 0]).T)
    assert ((hop >= 3.0) & (hop <= 20.0)).all()
    assert (paths[:, 1, 0] <= 5.0).all()  # 3 m short of the U's closed end at x = 8
    # after v2 the waypoints are evenly spaced on the straight leg to the goal
    leg = np.diff(paths[:, 2:], axis=1)
    assert np.hypot(*leg.transpose(2, 0, 1)) == pytest.approx(np.repeat(np.hypot(*leg[:, :1].transpose(2, 0, 1)), 5, axis=1))


def _wall():
    """A wall of points across the start-goal line: x = 50, y from -15 to 15 every metre."""
    return np.column_stack([np.full(31, 50.0), np.arange(-15.0, 16.0)])


def test_a_plan_is_deterministic_and_gets_round_a_wall():
    p = ga.GaParams()
    a = ga.plan((0, 0), (100, 0), _wall(), p, np.random.default_rng(5), bounds=(-50, -50, 150, 50))
    b = ga.plan((0, 0), (100, 0), _wall(), p, np.random.default_rng(5), bounds=(-50, -50, 150, 50))
    assert np.array_equal(a.path, b.path) and a.best_fitness == b.best_fitness
    assert a.usable and a.clearance_m >= p.safety_radius_m
    assert a.generation_usable is not None and a.generation_usable <= 20
    # round the end of the wall (15 m + 3 m out): at least 2 * hypot(50, 18) = 106.3 m, not much more
    assert 106.2 < ga.path_lengths(a.path[None])[0] < 125.0
    assert ((a.path[:, 0] >= -50) & (a.path[:, 0] <= 150) & (np.abs(a.path[:, 1]) <= 50)).all()


def test_resample_keeps_ends_and_spaces_evenly():
    out = ga.resample([[0, 0], [10, 0], [10, 10]], 5)
    assert out.tolist() == [[0, 0], [5, 0], [10, 0], [10, 5], [10, 10]]


@pytest.mark.parametrize("key, value, expected", [("waypoints", 2, "an integer >= 3"),
                                                  ("mutation_threshold", 1.5, "a number in [0, 1]"),
                                                  ("smooth_threshold", 1.0, "a number > 1")])
def test_bad_planner_parameters_are_one_line_errors(tmp_path, key, value, expected):
    r = cli_in_process("run", SCENARIOS / "planner" / "field.toml", "--set", f"controllers.ga_planner.{key}={value}",
                       "--out", tmp_path / "o")
    assert r.returncode == 2 and not (tmp_path / "o").exists()
    assert f"key 'controllers.ga_planner.{key}': expected {expected}, got {value}" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
