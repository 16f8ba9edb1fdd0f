"""The plug-in's 2-D time to collision (sumo_avoid.metrics.ttc), pinned to hand-computed cases
(m, s, rad; cars 4 m x 2 m unless said otherwise), and its pruned search against brute force."""
import math

import numpy as np
import pandas as pd
import pytest

from sumo_avoid.metrics.ttc import TTC2D, min_ttc2d_s, ttc_rectangles


def ttc(a, b, horizon_s=10.0):
    """a, b: (x, y, heading, vx, vy[, length, width])."""
    def unpack(c):
        x, y, h, vx, vy, *lw = c
        lng, wid = lw if lw else (4.0, 2.0)
        return [x, y], h, lng, wid, [vx, vy]

    (ca, ha, la, wa, va), (cb, hb, lb, wb, vb) = unpack(a), unpack(b)
    return float(ttc_rectangles(ca, ha, la, wa, va, cb, hb, lb, wb, vb, horizon_s)[0])


def test_head_on():
    # centres 30 m apart on one line, noses 30 - 2 - 2 = 26 m apart, closing at 10 + 10 m/s: 1.3 s
    assert ttc((0, 0, 0, 10, 0), (30, 0, math.pi, -10, 0)) == pytest.approx(1.3)


def test_rear_end():
    # follower at 20 m/s, leader 20 m ahead at 10 m/s: gap 20 - 4 = 16 m, closing 10 m/s: 1.6 s
    assert ttc((0, 0, 0, 20, 0), (20, 0, 0, 10, 0)) == pytest.approx(1.6)


def test_passing_beside_never_touches():
    # the same closing speed, but 3 m to the side: lateral gap 3 - 1 - 1 = 1 m stays: no contact
    assert ttc((0, 0, 0, 20, 0), (20, 3, 0, 10, 0)) == math.inf
    # and a lateral gap of exactly 0 (2 m apart) is contact (touching counts): TTC as rear-end
    assert ttc((0, 0, 0, 20, 0), (20, 2, 0, 10, 0)) == pytest.approx(1.6)


def test_crossing_at_right_angles():
    # a eastbound at 10 m/s from (0,0); b northbound at 10 m/s from (20,-20).
    # x overlap: a's front 2 + 10t >= b's left side 19 -> t >= 1.7 (until a's rear passes 21: 2.3)
    # y overlap: b's front -18 + 10t >= a's right side -1 -> t >= 1.7 (until 2.3): contact at 1.7
    assert ttc((0, 0, 0, 10, 0), (20, -20, math.pi / 2, 0, 10)) == pytest.approx(1.7)
    # b starts 10 m later: it reaches y = -1 at 2.7 s, a has left x <= 21 at 2.3 s: they miss
    assert ttc((0, 0, 0, 10, 0), (20, -30, math.pi / 2, 0, 10)) == math.inf


def test_rotated_rectangle_uses_its_own_axes():
    # a: 2 x 2 square turned 45 degrees at the origin, standing; b: 2 x 2 square at (10, 0) coming
    # at 1 m/s. a's corner reaches x = sqrt(2); b's left side is at 9 - t: contact at 9 - sqrt(2)
    # (on a's own axes the projections already overlap from 8 - sqrt(2) on, so that is not it)
    t = ttc((0, 0, math.pi / 4, 0, 0, 2, 2), (10, 0, 0, -1, 0, 2, 2))
    assert t == pytest.approx(9 - math.sqrt(2))


def test_overlapping_now_is_zero_and_apart_or_late_is_inf():
    assert ttc((0, 0, 0, 0, 0), (3, 0, 0, 0, 0)) == 0.0  # rear 1 m inside the other's front
    assert ttc((0, 0, 0, 0, 0), (10, 0, 0, 0, 0)) == math.inf  # standing, apart
    assert ttc((0, 0, 0, 10, 0), (20, 0, 0, 20, 0)) == math.inf  # the one ahead is faster
    # 204 m at 10 m/s closing: 20 s, beyond the 10 s horizon; within a 25 s one
    assert ttc((0, 0, 0, 20, 0), (204, 0, 0, 10, 0)) == math.inf
    assert ttc((0, 0, 0, 20, 0), (204, 0, 0, 10, 0), horizon_s=25.0) == pytest.approx(20.0)
    # the contact lies in the past (b has passed a): none
    assert ttc((0, 0, 0, 0, 0), (-10, 0, 0, -5, 0)) == math.inf


def row(step, vid, ego, x, y, heading, vx, vy, length=4.0, width=2.0):
    return {"step": step, "time_s": 0.1 * step, "id": vid, "is_ego": ego, "x": x, "y": y, "vx": vx, "vy": vy, "speed": math.hypot(vx, vy),
                "heading": heading, "length": length, "width": width}


def test_min_over_the_run_clamped_at_the_horizon():
    rows = [row(0, "e", True, 0, 0, 0, 20, 0), row(0, "lead", False, 20, 0, 0, 10, 0),  # 1.6 s
            row(1, "e", True, 2, 0, 0, 20, 0), row(1, "lead", False, 21, 0, 0, 10, 0),  # 1.5 s
            row(1, "n1", False, 100, 50, 0, 0, 0), row(1, "n2", False, 103, 50, 0, 0, 0)]  # non-egos touching
    assert min_ttc2d_s(pd.DataFrame(rows)) == pytest.approx(1.5)
    alone = pd.DataFrame([row(0, "e", True, 0, 0, 0, 20, 0), row(0, "far", False, 0, 500, 0, 0, 0)])
    assert min_ttc2d_s(alone) == TTC2D().horizon_s
    assert min_ttc2d_s(pd.DataFrame([row(0, "n", False, 0, 0, 0, 1, 0)])) is None


def test_a_fast_pair_far_apart_is_found():
    # head-on at 30 m/s each, 150 m apart: (150 - 4) / 60 = 2.43 s, although the first search
    # radius (a diagonal + 1 m) holds no pair at all
    rows = [row(0, "e", True, 0, 0, 0, 30, 0), row(0, "o", False, 150, 0, math.pi, -30, 0),
            row(0, "s", False, 0, 40, 0, 0, 0)]
    assert min_ttc2d_s(pd.DataFrame(rows)) == pytest.approx(146 / 60)


def test_pruned_search_equals_brute_force_on_random_tables():
    rng = np.random.default_rng(3)
    for _ in range(5):
        rows = []
        for step in range(20):
            for k in range(12):
                h = rng.uniform(-math.pi, math.pi)
                v = rng.uniform(0, 25)
                rows.append(row(step, f"v{k}", k < 3, *rng.uniform(0, 800, 2), h, v * math.cos(h), v * math.sin(h),
                                rng.uniform(3, 12), rng.uniform(1.6, 2.6)))
        df = pd.DataFrame(rows)
        brute = TTC2D().horizon_s
        for _, g in df.groupby("step"):
            e, o = g[g.is_ego], g
            for _, a in e.iterrows():
                for _, b in o.iterrows():
                    if a.id != b.id:
                        brute = min(brute, ttc((a.x, a.y, a.heading, a.vx, a.vy, a.length, a.width),
                                               (b.x, b.y, b.heading, b.vx, b.vy, b.length, b.width)))
        assert min_ttc2d_s(df) == pytest.approx(brute, abs=1e-12)
