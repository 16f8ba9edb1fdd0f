"""The formation controller in real SUMO (libsumo, the arena net): the width ratio's modes through
two gaps (kappa 2, then 3, then re-forming), byte-identical metrics for a seed, seeded obstacle
layouts, and bad formation input as one line."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import SCENARIOS, cli_in_process

from sumo_avoid.runs import outputs as evaluate
from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs import runner
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.obstacles import RandomObstaclesConfig, draw

GAP = SCENARIOS / "formation" / "gap.toml"
ARENA = SCENARIOS / "formation" / "arena_g1.toml"


def test_gap_narrows_then_breaks_up_and_reforms():
    res = runner.run(scenario.load(GAP))
    m = evaluate.run_metrics(res)
    assert m["goal_reached"] and m["collisions"] == 0 and m["obstacle_hits"] == 0
    log = m["formation_mode_log"]
    assert [k for _, k in log] == [2, 3, 1]
    t = res.traj
    lead = t[t["id"] == "f0"].set_index("time_s")["x"]
    x2, x3, x1 = (float(lead.loc[round(tt, 1)]) for tt, _ in log)
    # kappa 2 before the 20 m gap (x 70-76), kappa 3 after it and before the 7 m gap (x 120-126),
    # kappa 1 again within 50 m behind the 7 m gap (measured: 46.9 m with the safety shield, 46.6 m
    # before it; the column of 5 is 40 m long)
    assert x2 < 70 and 76 < x3 < 120 and 126 < x1 <= 126 + 50
    # narrowed through the first gap: the members' spread while the leader passes it fits the 20 m gap
    at_gap = t[t["time_s"].isin(lead[(lead >= 62) & (lead <= 76)].index)]
    assert at_gap.groupby("time_s")["y"].agg(lambda y: y.max() - y.min()).max() < 20.0 - 1.8
    # broken up through the second: every member crosses x = 123 inside the 7 m gap (y 121.5-128.5)
    for _, g in t.groupby("id"):
        assert abs(float(g.iloc[(g["x"] - 123.0).abs().argmin()]["y"]) - 125.0) < 3.5 - 0.9
    assert 0 < m["kappa2_share"] < 1 and 0 < m["kappa3_share"] < 1
    assert m["kappa1_share"] + m["kappa2_share"] + m["kappa3_share"] == pytest.approx(1.0)


def test_same_seed_same_metrics_and_obstacles_follow_the_seed(tmp_path):
    sets = ["sim.duration_s=20", "output.plots=false"]
    out = []
    for k in range(2):
        res = runner.run(scenario.load(ARENA, sets, seed=3))
        evaluate.write_outputs(res, tmp_path / str(k), plots=False)
        out.append((tmp_path / str(k) / "metrics.json").read_bytes())
    assert out[0] == out[1]
    a = scenario.load(ARENA, seed=3).spec.obstacles
    b = scenario.load(ARENA, seed=4).spec.obstacles
    assert len(a) == len(b) == 40 and a != b
    assert a == scenario.load(ARENA, seed=3).spec.obstacles


def test_random_obstacles_keep_clear_and_apart():
    cfg = RandomObstaclesConfig(count=60, region=(0.0, 0.0, 100.0, 100.0), radius_min_m=1.0, radius_max_m=2.0,
                                keep_clear=((50.0, 50.0),), clear_radius_m=10.0, min_gap_m=3.0)
    polys = draw(cfg, seed=5)
    centres = np.array([p.mean(axis=0) for p in polys])
    radii = np.array([np.hypot(*(p - p.mean(axis=0)).T).max() for p in polys])
    assert len(polys) == 60 and all(p.shape == (8, 2) for p in polys)
    assert (np.hypot(*(centres - 50.0).T) - radii >= 10.0 - 1e-9).all()
    d = np.hypot(*(centres[:, None] - centres[None]).transpose(2, 0, 1)) - radii[:, None] - radii[None]
    assert (d[~np.eye(60, dtype=bool)] >= 3.0 - 1e-9).all()
    assert ((radii >= 1.0 - 1e-9) & (radii <= 2.0 + 1e-9)).all()
    with pytest.raises(ValueError, match="could not place"):
        draw(RandomObstaclesConfig(count=60, region=(0.0, 0.0, 20.0, 20.0), min_gap_m=0.0), seed=1, max_tries=2000)
    with pytest.raises(ValueError, match="cannot fit"):  # more than hexagonal packing allows: at once
        draw(RandomObstaclesConfig(count=500, region=(0.0, 0.0, 20.0, 20.0)), seed=1)


@pytest.mark.parametrize("override, key", [
    ("random_obstacles.region=[0.0, 0.0, -5.0, 10.0]", "random_obstacles.region"),
    ("random_obstacles.count=5000", "random_obstacles.count"),
    ("arena.starts=[[0.0, 0.0]]", "arena.starts"),
    ("controllers.formation.shape=\"blob\"", "controllers.formation.shape"),
    ("controllers.formation.beta=1.5", "controllers.formation.beta"),
    ("ego.goals.f0=[400.0, 10.0]", "ego.goals.f0"),
])
def test_bad_formation_input_is_one_line(tmp_path, override, key):
    with pytest.raises(ScenarioError) as e:
        scenario.load(ARENA, [override])
    assert e.value.key == key and "\n" not in str(e.value)
    r = cli_in_process("run", ARENA, "--set", override, "--out", tmp_path / "out")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and f"'{key}'" in r.stderr
    assert not (tmp_path / "out").exists()
