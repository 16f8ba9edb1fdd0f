"""The ``policy`` controller: its observation vector (layout and bounds), its actions, and the one-line
errors for a policy it cannot use (the key named, exit code 2)."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from conftest import OVERTAKING, ROOT

from sumo_avoid.control import policy_obs
from sumo_avoid.control.policy import PolicyParams, action_bounds, load_policy
from sumo_avoid.control.policy_examples import KeepLane
from sumo_avoid.core.config import FieldError
from sumo_avoid.actuation.kinematic import KinematicParams


def test_the_layout_names_every_entry_and_bounds_it():
    p = PolicyParams(k_nearest=3, route_points=4)
    names = policy_obs.names(p)
    lo, hi = policy_obs.bounds(p)
    assert len(names) == policy_obs.size(p) == 5 + 2 + 4 * 4 + 7 * 3 == len(lo) == len(hi)
    assert names[:7] == ["speed_mps", "d_m", "heading_rad", "v_s_mps", "v_d_mps", "goal_ds_m", "goal_dd_m"]
    assert names[7] == "route0.x_m" and names[-1] == "other2.width_m"
    assert (lo < hi).all() and lo[names.index("other1.present")] == 0.0 and hi[names.index("other1.ds_m")] == 80.0


def test_action_bounds_follow_the_actuator_and_the_parameters():
    lim = KinematicParams(max_accel_mps2=2.0, max_decel_mps2=6.0, max_yaw_rate_radps=0.5, max_reverse_speed_mps=1.0)
    lo, hi = action_bounds(PolicyParams(action="accel_yaw"), lim)
    assert lo.tolist() == [-6.0, -0.5] and hi.tolist() == [2.0, 0.5]
    lo, hi = action_bounds(PolicyParams(max_speed_mps=20.0, max_lateral_speed_mps=2.0), lim)
    assert lo.tolist() == [-1.0, -2.0] and hi.tolist() == [20.0, 2.0]


def test_keep_lane_follows_the_lane_and_brakes_behind_a_slower_car_ahead():
    p = PolicyParams()
    x = np.zeros(policy_obs.size(p), np.float32)
    x[policy_obs.names(p).index("d_m")] = 1.0
    x[policy_obs.names(p).index("v_s_mps")] = 15.0
    assert KeepLane()(x).tolist() == [15.0, -0.5]  # cruise, back to the centre
    j = policy_obs.names(p).index("other0.present")
    x[j:j + 7] = [1.0, 15.0, 0.2, -10.0, 0.0, 4.5, 1.8]  # 15 m ahead at 5 m/s
    v, _ = KeepLane()(x)
    assert 0.0 <= v < 10.0


def test_a_policy_that_is_no_import_path_or_does_not_import_is_refused_naming_the_key():
    with pytest.raises(FieldError) as e:
        PolicyParams(policy="keep lane")
    assert e.value.key == "policy"
    with pytest.raises(FieldError) as e:
        PolicyParams(action="steer")
    assert e.value.key == "action"
    with pytest.raises(FieldError, match="ModuleNotFoundError") as e:
        load_policy("sumo_avoid.control.no_such_module:KeepLane")
    assert e.value.key == "controllers.policy.policy"
    with pytest.raises(FieldError, match="AttributeError"):
        load_policy("sumo_avoid.control.policy_examples:KeepLain")
    assert load_policy("sumo_avoid.control.policy_examples:KeepLane")(np.zeros(103))[0] == 15.0


@pytest.mark.parametrize("extra", [[], ["--set", "controllers.policy.policy=sumo_avoid.control.policy_examples:KeepLain"]])
def test_run_refuses_a_policy_it_cannot_load_in_one_line(tmp_path, extra):
    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-m", "sumo_avoid.cli", "run", str(OVERTAKING), "--controller", "policy", *extra,
                        "--set", "sim.duration_s=1", "--out", str(out), "--no-plots", "--quiet"], cwd=ROOT,
                       capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "'controllers.policy.policy'" in r.stderr, r.stderr
    assert not out.exists()


def test_a_suite_compares_the_scripted_policy_with_apf_sa_on_the_same_runs(tmp_path, capsys):
    from sumo_avoid.cli import main

    suite = tmp_path / "suite.toml"
    suite.write_text(f'''[defaults]
seeds = "1"
set = ["output.plots=false", "sim.duration_s=8"]

[[entry]]
name = "apf_sa"
scenario = "{OVERTAKING.as_posix()}"
controller = "apf_sa"
criteria = ["collisions == 0"]

[[entry]]
name = "keep_lane"
scenario = "{OVERTAKING.as_posix()}"
controller = "policy"
set = ["controllers.policy.policy='sumo_avoid.control.policy_examples:KeepLane'"]
criteria = ["collisions == 0", "mean_speed_mps_max <= 16"]
''')
    rc = main(["suite", str(suite), "--ledger", str(tmp_path / "ledger.sqlite"), "--workers", "2", "--quiet"])
    out = capsys.readouterr().out
    assert rc == 0 and "2 of 2 entries passed" in out, out
