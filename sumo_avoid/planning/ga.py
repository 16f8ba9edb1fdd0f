"""The genetic-algorithm path planner of seed 004 (SPEC §4): fitness, the four operators, the GA.

A chromosome is a path of n waypoints WP_1..WP_n, WP_1 the start and WP_n the goal (both fixed); a
population is an (N, n, 2) array. Obstacles are points (what the radar reported, see
:mod:`sumo_avoid.planning.radar_map`); the clearance of a path is the smallest distance from any
of its segments to any obstacle point. Fitness (SPEC §4, eq. 1-4, larger is better, max_k over
the population):

    length(p)   = 1 - L(p) / max_k L(p_k)                          L = summed segment lengths
    obstacle(p) = min_i 0.01 / (0.01 + exp(-4.6 dist(WP_i WP_i+1, obs) / R_radar))
    smooth(p)   = S(p) / max_k S(p_k),  S = sum_{i=2}^{n-1} |WP_i-1 WP_i+1| / (|WP_i-1 WP_i| + |WP_i WP_i+1|)
    Fitness(p)  = w_L length(p) + w_o obstacle(p) + w_s smooth(p)

Operators (seed §2.3): single-point crossover (two paths swap their first c waypoints), mutation
(a waypoint moves, by a Gaussian step, when its uniform draw exceeds T_m), regression (inner
waypoints pulled towards the straight start-goal segment, kept only where the path stays
collision-free) and smoothing (WP_i replaced by the midpoint of WP_i-1 WP_i+1 when
(|WP_i-1 WP_i| + |WP_i WP_i+1|) / |WP_i-1 WP_i+1| > T_s).

Where the seed is silent (selection, elitism, initialisation, stopping), this module chooses:
a path is *usable* when its clearance is at least ``safety_radius_m``; ranking puts usable paths
first, by fitness, then the others by clearance (feasibility first, Deb's rule: the seed's obstacle term is ~0.01 at
contact and barely changes within metres of an obstacle, so it cannot on its own keep a path off
one); ``elite`` best paths survive unchanged; parents by binary tournament on that ranking. A plan
stops after ``generations`` or once its best path is usable and has stayed the same for
``patience`` generations. Everything random comes from one ``numpy.random.Generator``: same
inputs and generator state, same plan.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.config import FieldError, field_doc
from sumo_avoid.planning import kernels


@dataclass(frozen=True)
class GaParams:
    waypoints: int = field_doc(8, doc="n, waypoints per path including start and goal (>= 3)")
    population: int = field_doc(40, doc="paths per generation (>= 4)")
    generations: int = field_doc(30, doc="most generations per plan")
    patience: int = field_doc(5, doc="a plan stops once its best path is usable and unchanged for this many generations")
    elite: int = field_doc(2, doc="best paths carried over unchanged into the next generation")
    w_length: float = field_doc(1.0, doc="w_L, weight of length()")
    w_obstacle: float = field_doc(8.0, doc="w_o, weight of obstacle()")
    w_smooth: float = field_doc(0.3, doc="w_s, weight of smooth()")
    radar_range_m: float = field_doc(100.0, positive=True, doc="R_radar in obstacle(): the radar's range, m")
    safety_radius_m: float = field_doc(3.0, doc="a path is usable (collision-free) when every segment keeps this "
                                                "clearance from every obstacle point, m")
    crossover_prob: float = field_doc(0.8, doc="probability that a pair of parents is crossed over")
    mutation_threshold: float = field_doc(0.7, doc="T_m: an inner waypoint moves when its U(0,1) draw exceeds T_m")
    mutation_sigma_m: float = field_doc(6.0, doc="standard deviation of a mutation step (each axis), m")
    regression_prob: float = field_doc(0.3, doc="probability that an offspring is offered the regression operator")
    regression_rate: float = field_doc(0.5, doc="regression moves each inner waypoint this fraction of the way "
                                                "to its foot on the start-goal segment")
    smooth_threshold: float = field_doc(1.15, doc="T_s of the smoothing operator (> 1)")
    init_spread_m: float = field_doc(25.0, doc="standard deviation of the initial waypoints' offset across the "
                                               "start-goal line, m")
    free_init_share: float = field_doc(0.25, doc="share of the initial population led out through free space: "
                                                 "start, two via points each reached by a collision-free segment, "
                                                 "then straight to the goal")
    free_init_reach_m: float = field_doc(30.0, positive=True, doc="those via points lie at most this far from "
                                                                  "the start and from each other, m")

    def __post_init__(self):
        for key, ok, what in (("waypoints", self.waypoints >= 3, "an integer >= 3"),
                              ("population", self.population >= 4, "an integer >= 4"),
                              ("generations", self.generations >= 1, "an integer >= 1"),
                              ("elite", self.elite < self.population, "an integer below population"),
                              ("smooth_threshold", self.smooth_threshold > 1.0, "a number > 1"),
                              *((k, getattr(self, k) <= 1.0, "a number in [0, 1]") for k in
                                ("crossover_prob", "mutation_threshold", "regression_prob", "regression_rate",
                                 "free_init_share"))):
            if not ok:
                raise FieldError(key, what, getattr(self, key))


# ------------------------------------------------------------------------------------------------
# fitness terms, vectorised over the population (N, n, 2)
# ------------------------------------------------------------------------------------------------
def path_lengths(pop) -> np.ndarray:
    """(N,) summed segment lengths L(p), m."""
    return np.hypot(*np.diff(pop, axis=1).transpose(2, 0, 1)).sum(axis=1)


def sorted_points(points) -> np.ndarray:
    """Obstacle points (P, 2) sorted by x, contiguous: the form the clearance kernel reads."""
    pts = np.asarray(points, float).reshape(-1, 2)
    return np.ascontiguousarray(pts[np.argsort(pts[:, 0], kind="stable")])


def _clearances(pop, pts):
    """(first segment (N,), other segments (N,)) clearances; ``pts`` from :func:`sorted_points`."""
    pop = np.ascontiguousarray(pop, float)
    if len(pts) == 0:
        return np.full(len(pop), np.inf), np.full(len(pop), np.inf)
    return kernels.clearance(pop, pts)


def clearance(pop, points) -> np.ndarray:
    """(N,) smallest distance from any segment of each path to any obstacle point, m (inf: no points)."""
    return np.minimum(*_clearances(pop, sorted_points(points)))


def obstacle_term(clear, radar_range_m: float) -> np.ndarray:
    """obstacle(p) from each path's clearance (SPEC §4 eq. 2): ~0.0099 at contact, 0.5 at one radar range."""
    return 0.01 / (0.01 + np.exp(-4.6 * np.asarray(clear, float) / radar_range_m))


def smooth_raw(pop) -> np.ndarray:
    """(N,) S(p) = sum over inner waypoints of |WP_i-1 WP_i+1| / (|WP_i-1 WP_i| + |WP_i WP_i+1|)
    (a term is 1 where both segments have zero length)."""
    seg = np.hypot(*np.diff(pop, axis=1).transpose(2, 0, 1))  # (N, n-1)
    chord = np.hypot(*(pop[:, 2:] - pop[:, :-2]).transpose(2, 0, 1))  # (N, n-2)
    around = seg[:, :-1] + seg[:, 1:]
    return np.where(around > 0, chord / np.where(around > 0, around, 1.0), 1.0).sum(axis=1)


def fitness_of(pop, clear, p: GaParams) -> np.ndarray:
    """(N,) SPEC §4 eq. 4 from the paths and their clearances (N,)."""
    L = path_lengths(pop)
    S = smooth_raw(pop)
    length = 1.0 - L / max(L.max(), 1e-12)
    smooth = S / S.max() if S.max() > 0 else np.zeros(len(pop))
    return p.w_length * length + p.w_obstacle * obstacle_term(clear, p.radar_range_m) + p.w_smooth * smooth


def fitness(pop, points, p: GaParams):
    """(fitness (N,), clearance (N,)) of every path (SPEC §4 eq. 4)."""
    pop = np.asarray(pop, float)
    c = clearance(pop, points)
    return fitness_of(pop, c, p), c


def violation(pop, points, radius_m: float, first_radius_m: float, presorted: bool = False):
    """(clearance (N,), violation (N,)): how far each path falls short of being usable, m (0 = usable),
    summed over its segments: its first segment must keep ``first_radius_m`` from every point, the
    others ``radius_m``. (The ego may already be closer than the safety radius to a point it has
    just discovered; every path starts there, so the first segment asks only that the ego not get
    closer.) The sum, not the worst segment: a path that clears one of several obstacles it crosses
    ranks better, so the GA can repair a path piece by piece. ``presorted``: ``points`` come from
    :func:`sorted_points`."""
    pts = points if presorted else sorted_points(points)
    c1, c2 = _clearances(pop, pts)
    if len(pts) == 0:
        return np.minimum(c1, c2), np.zeros(len(c1))
    v = kernels.shortfall(np.ascontiguousarray(pop, float), pts, float(first_radius_m), float(radius_m))
    return np.minimum(c1, c2), np.maximum(v, 0.0)


# ------------------------------------------------------------------------------------------------
# operators (pure: every random draw is an argument)
# ------------------------------------------------------------------------------------------------
def crossover(a, b, cut: int):
    """Single-point crossover: the two paths swap their first ``cut`` waypoints (returns new arrays)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.concatenate([b[:cut], a[cut:]]), np.concatenate([a[:cut], b[cut:]])


def mutate(pop, draws, steps, threshold: float):
    """Inner waypoint i of path k moves by ``steps[k, i]`` where ``draws[k, i] > threshold``
    (draws (N, n) uniform, steps (N, n, 2) m); start and goal never move."""
    out = np.array(pop, float)
    move = np.asarray(draws) > threshold
    move[:, [0, -1]] = False
    out[move] += np.asarray(steps, float)[move]
    return out


def regress(pop, points, rate: float, safety_radius_m: float, first_radius_m: float | None = None,
            presorted: bool = False):
    """Pull every inner waypoint ``rate`` of the way towards its foot on the straight start-goal
    segment; a path keeps the move only if it stays usable (:func:`violation` 0; by default the
    first segment too needs ``safety_radius_m``). Returns (paths, moved (N,) bool)."""
    pop = np.asarray(pop, float)
    s, g = pop[:, :1], pop[:, -1:]
    d = g - s
    den = (d * d).sum(-1)
    t = np.clip(((pop - s) * d).sum(-1) / np.where(den > 0, den, 1.0), 0.0, 1.0)
    foot = s + t[..., None] * d
    cand = pop + rate * (foot - pop)
    cand[:, [0, -1]] = pop[:, [0, -1]]
    first = safety_radius_m if first_radius_m is None else first_radius_m
    ok = violation(cand, points, safety_radius_m, first, presorted)[1] <= 0.0
    return np.where(ok[:, None, None], cand, pop), ok


def smooth(pop, threshold: float):
    """Smoothing operator, in waypoint order (each test sees the already smoothed predecessor):
    WP_i becomes the midpoint of WP_i-1 WP_i+1 when (|WP_i-1 WP_i| + |WP_i WP_i+1|) / |WP_i-1 WP_i+1| > T_s."""
    return kernels.smooth(np.array(pop, float), float(threshold))


# ------------------------------------------------------------------------------------------------
# the GA
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Plan:
    path: np.ndarray  # (n, 2) best path, m
    usable: bool  # collision-free: violation 0 (clearance >= safety radius; first segment: see violation())
    clearance_m: float
    best_fitness: tuple[float, ...]  # best fitness (usable first) of generation 0, 1, ...
    generation_usable: int | None  # first generation with a usable path (0 = initial population)

    @property
    def generations(self) -> int:
        return len(self.best_fitness) - 1


def resample(path, n: int) -> np.ndarray:
    """(n, 2) points evenly spaced in arc length along a polyline (its ends kept)."""
    path = np.asarray(path, float)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    s = np.linspace(0.0, cum[-1], n)
    return np.column_stack([np.interp(s, cum, path[:, 0]), np.interp(s, cum, path[:, 1])])


def initial_population(start, goal, p: GaParams, rng: np.random.Generator, bounds, warm=None) -> np.ndarray:
    """The straight line; the warm path (resampled) and mutated copies of it for a quarter of the
    population; the rest straight-line stations offset across the line by N(0, init_spread_m)."""
    n, N = p.waypoints, p.population
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    line = start + np.linspace(0.0, 1.0, n)[:, None] * (goal - start)
    d = goal - start
    normal = np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-12)
    pop = line[None] + rng.normal(0.0, p.init_spread_m, (N, n, 1)) * normal
    pop[:, [0, -1]] = start, goal
    pop[0] = line
    if warm is not None:
        w = resample(warm, n)
        w[0], w[-1] = start, goal
        k = max(1, N // 4)
        pop[1:k + 1] = w
        pop[2:k + 1] = mutate(pop[2:k + 1], rng.random((k - 1, n)), rng.normal(0.0, p.mutation_sigma_m, (k - 1, n, 2)),
                              p.mutation_threshold)
    return clip(pop, bounds)


def free_space_paths(start, goal, k: int, n: int, points, p: GaParams, rng: np.random.Generator, bounds,
                     first_radius_m: float, tries: int = 8) -> np.ndarray:
    """Up to ``k`` paths (k', n, 2) that leave ``start`` through free space: a first via point v1
    in a random direction at U(safety_radius, reach) from the start, kept when the segment there
    keeps ``first_radius_m`` and v1 itself the safety radius from every point; a second v2 the same
    way from v1 (both segments and points at the safety radius); then straight on to the goal, the
    remaining waypoints evenly along that leg. ``tries`` candidates per path (vectorised); a v1
    without a free v2 goes straight on from v1; fewer than ``k`` paths when fewer v1 are free.
    ``points`` from :func:`sorted_points`. (Perturbing the straight start-goal line never finds a
    way out that begins away from the goal: down the channel the ego stands in, back round an
    obstacle.)"""
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    r, reach = p.safety_radius_m, max(p.free_init_reach_m, p.safety_radius_m)

    def hop(frm, first):
        """(M, 2) a random point from each of ``frm`` (M, 2), and whether it and the segment are free."""
        a = rng.uniform(0.0, 2.0 * np.pi, len(frm))
        to = frm + rng.uniform(r, reach, len(frm))[:, None] * np.column_stack([np.cos(a), np.sin(a)])
        to = clip(np.stack([frm, to, to], axis=1), bounds)[:, 1]  # (M, 3, 2): the waypoint kept inside
        if len(points) == 0:
            return to, np.ones(len(frm), bool)
        seg, _ = kernels.clearance(np.ascontiguousarray(np.stack([frm, to], axis=1)), points)
        at, _ = kernels.clearance(np.ascontiguousarray(np.stack([to, to], axis=1)), points)
        return to, (seg >= first) & (at >= r)

    v1, ok = hop(np.repeat(start[None], k * tries, axis=0), first_radius_m)
    v1 = v1[ok][:k]
    if len(v1) == 0 or n < 3:
        return np.zeros((0, n, 2))
    v2, ok2 = hop(np.repeat(v1, tries, axis=0), r)
    ok2 = ok2.reshape(len(v1), tries)
    pick = np.where(ok2.any(axis=1), np.argmax(ok2, axis=1), -1)
    v2 = np.where((pick >= 0)[:, None], v2.reshape(len(v1), tries, 2)[np.arange(len(v1)), np.maximum(pick, 0)], v1)
    m = n - 3  # waypoints after v2 on the straight leg to the goal (the goal included)
    if m < 1:  # n = 3: start, v1, goal
        return np.stack([np.repeat(start[None], len(v1), 0), v1, np.repeat(goal[None], len(v1), 0)], axis=1)
    leg = v2[:, None] + np.linspace(0.0, 1.0, m + 1)[None, 1:, None] * (goal - v2)[:, None]
    return np.concatenate([np.repeat(start[None, None], len(v1), 0), v1[:, None], v2[:, None], leg], axis=1)


def clip(pop, bounds):
    """Waypoints kept inside the box ``bounds`` = (xmin, ymin, xmax, ymax), or by ``bounds(pop)`` when
    it is a function (the road's corridor, :func:`sumo_avoid.planning.corridor.corridor_clip`), or
    unchanged if None."""
    if bounds is None:
        return pop
    if callable(bounds):
        return bounds(pop)
    lo, hi = np.asarray(bounds[:2], float), np.asarray(bounds[2:], float)
    out = pop.copy()
    out[:, 1:-1] = np.clip(pop[:, 1:-1], lo, hi)
    return out


def _ranking(f, v):
    """Indices best first (Deb's rule): usable paths (violation v == 0) by fitness, then the others
    by violation, the least first. Stable: ties keep their order."""
    usable = v <= 0.0
    return np.lexsort((np.where(usable, -f, v), ~usable))


def next_generation(pop, order, p: GaParams, points, rng: np.random.Generator, bounds, first_radius_m) -> np.ndarray:
    """Elites, then offspring of tournament parents: crossover, mutation, regression, smoothing
    (``points`` from :func:`sorted_points`)."""
    N, n = pop.shape[:2]
    rank = np.empty(N, int)
    rank[order] = np.arange(N)
    kids = N - p.elite
    pairs = (kids + 1) // 2
    duel = rng.integers(0, N, (2 * pairs, 2))  # binary tournaments
    parents = np.where(rank[duel[:, 0]] <= rank[duel[:, 1]], duel[:, 0], duel[:, 1])
    a, b = pop[parents[0::2]], pop[parents[1::2]]
    cuts = rng.integers(1, n - 1, pairs)
    cross = rng.random(pairs) < p.crossover_prob
    k = np.arange(n)[None, :, None] < cuts[:, None, None]
    swap = k & cross[:, None, None]
    a2, b2 = np.where(swap, b, a), np.where(swap, a, b)  # crossover() for every pair at once
    off = np.concatenate([a2, b2])[:kids]
    off = mutate(off, rng.random((kids, n)), rng.normal(0.0, p.mutation_sigma_m, (kids, n, 2)), p.mutation_threshold)
    off = clip(off, bounds)
    offer = rng.random(kids) < p.regression_prob
    if offer.any():
        off[offer] = regress(off[offer], points, p.regression_rate, p.safety_radius_m, first_radius_m, True)[0]
    off = smooth(off, p.smooth_threshold)
    return np.concatenate([pop[order[:p.elite]], off])


def plan(start, goal, points, p: GaParams, rng: np.random.Generator, bounds=None, warm=None) -> Plan:
    """Run the GA from ``start`` to ``goal`` around obstacle ``points`` (P, 2)."""
    points = sorted_points(points)
    r = p.safety_radius_m
    d0 = float(np.hypot(*(points - np.asarray(start, float)).T).min()) if len(points) else np.inf
    first = min(r, d0 - 0.01)
    pop = initial_population(start, goal, p, rng, bounds, warm)
    k = min(round(p.free_init_share * p.population), p.population - 1 - p.population // 4)
    if k > 0:  # the last k paths (the line offsets) give way to paths led out through free space
        free = free_space_paths(start, goal, k, p.waypoints, points, p, rng, bounds, first)
        if len(free):
            pop[len(pop) - len(free):] = clip(free, bounds)
    history: list[float] = []
    usable_at = None
    best, same = None, 0
    for gen in range(p.generations + 1):
        c, v = violation(pop, points, r, first, presorted=True)
        f = fitness_of(pop, c, p)
        order = _ranking(f, v)
        top = order[0]
        history.append(float(f[top]))
        usable = bool(v[top] <= 0.0)
        if usable and usable_at is None:
            usable_at = gen
        same = same + 1 if best is not None and np.array_equal(pop[top], best) else 0
        best = pop[top].copy()
        if gen == p.generations or (usable and same >= p.patience):
            return Plan(best, usable, float(c[top]), tuple(history), usable_at)
        pop = next_generation(pop, order, p, points, rng, bounds, first)
    raise AssertionError("unreachable")
