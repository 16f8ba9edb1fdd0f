"""Bad input everywhere (issue 17): a table of bad inputs over every command, each checked by
:func:`corpus.check`: exit code 2, exactly one stderr line naming the file and the key or flag, no
traceback, nothing written anywhere under the test's folder (the working directory of the call).

Families: scenario TOML (syntax, keys, types, values, relations); SUMO inputs (nets, routes,
additional files, egos); every command and flag; batch and suite files; ledgers and report inputs;
file-system errors. Most are caught before SUMO starts and run in this process; ``sub`` cases run
the real command in a process of its own.
"""
from __future__ import annotations

import sqlite3
import warnings

import pytest
from conftest import cli_in_process
from corpus import NET, ROOT, ROUTES, Call, Case, base, check, scenario

SCN = ROOT / "scenarios" / "overtaking.toml"
ARENA = ROOT / "scenarios" / "arena_v4.toml"


def _flag(argv, names, sub=False, xfail=None, family="cli") -> Case:
    """A command line (``{tmp}`` in an argument is the test's folder)."""
    def make(tmp):
        return Call([str(a).replace("{tmp}", str(tmp)) for a in argv], tuple(n.replace("{tmp}", str(tmp))
                                                                           for n in names), cwd=tmp)
    return Case(family, make, sub, xfail)


OBST = '[[obstacles]]\nid = "a"\nshape = {shape}\n'
SQ = "[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]"

CASES: dict[str, Case] = {
    # --- scenario TOML: syntax, keys, types --------------------------------------------------------
    "toml_syntax": scenario(base().replace('name = "bad"', 'name = "bad'), "<syntax>"),
    "toml_binary_junk": scenario(b"\x00\xff\xfe\x89PNG\r\n\x1a\n\x00\x00", "<syntax>"),
    "toml_not_utf8": scenario(base().encode().replace(b'"bad"', b'"b\xe9d"'), "<syntax>"),
    "toml_empty": scenario("", "name"),
    "toml_unknown_top_key": scenario(base("colour = 3"), "colour"),
    "toml_unknown_sim_key": scenario(base(sim="stepp_s = 0.1"), "sim.stepp_s"),
    "toml_unknown_arena_key": scenario(base("[arena]\nsizee_m = 10.0"), "arena.sizee_m"),
    "toml_unknown_controller_param": scenario(base("[controllers.apf_sa]\nk_rpe = 1.0"), "controllers.apf_sa.k_rpe"),
    "toml_sim_not_table": scenario('name = "bad"\nsim = 3\n[ego]\nids = ["ego"]\n', "sim"),
    "toml_type_duration": scenario(base(sim='duration_s = "long"').replace("duration_s = 3.0\n", ""),
                                   "sim.duration_s"),
    "toml_type_bool_number": scenario(base(ego="cruise_speed_mps = true"), "ego.cruise_speed_mps"),
    "toml_type_ids": scenario(base(ids='"ego"'), "ego.ids"),
    "toml_type_seed_float": scenario(base(sim="seed = 1.5"), "sim.seed"),
    "toml_nan": scenario(base("[actuators.kinematic]\nmax_accel_mps2 = nan"), "actuators.kinematic.max_accel_mps2"),
    "toml_inf": scenario(base("[actuators.kinematic]\nmax_decel_mps2 = inf"), "actuators.kinematic.max_decel_mps2"),
    "toml_unknown_layer_param": scenario(base("[layers.traffic]\nstop_margn_m = 1.0"), "layers.traffic.stop_margn_m"),
    "toml_unknown_sensor_param": scenario(base("[sensors.radar]\nfov = 60.0"), "sensors.radar.fov"),
    "val_radar_person_range": scenario(base("[sensors.radar]\nperson_range_factor = 2.0"),
                                       "sensors.radar.person_range_factor"),
    "val_vru_margin_negative": scenario(base("[controllers.apf_sa]\nvru_margin_m = -1.0"),
                                        "controllers.apf_sa.vru_margin_m"),
    "toml_type_ego_layers": scenario(base(ego='layers = "traffic"'), "ego.layers"),
    "toml_missing_name": scenario(base().replace('name = "bad"\n', ""), "name"),
    "toml_missing_net": scenario(base().replace(f'net = "{NET}"\n', ""), "sim.net"),
    # --- scenario values and relations -----------------------------------------------------------
    "val_duration_negative": scenario(base(sim="duration_s = -1.0").replace("duration_s = 3.0\n", ""),
                                      "sim.duration_s"),
    "val_step_zero": scenario(base(sim="step_s = 0.0"), "sim.step_s"),
    "val_step_over_duration": scenario(base(sim="step_s = 5.0"), "sim.step_s"),
    "val_step_tiny": scenario(base(sim="step_s = 1e-9"), "sim.step_s"),
    "val_step_not_ms": scenario(base(sim="step_s = 0.0125"), "sim.step_s"),
    "val_duration_huge": scenario(base(sim="duration_s = 1e12").replace("duration_s = 3.0\n", ""),
                                  "sim.duration_s"),
    "val_seed_negative": scenario(base(sim="seed = -1"), "sim.seed"),
    "val_seed_2_31": scenario(base(sim="seed = 2147483648"), "sim.seed"),
    "val_lateral_resolution_zero": scenario(base(sim="lateral_resolution_m = 0.0"), "sim.lateral_resolution_m"),
    "val_cruise_negative": scenario(base(ego="cruise_speed_mps = -5.0"), "ego.cruise_speed_mps"),
    "val_goal_tolerance_negative": scenario(base(ego="goal_tolerance_m = -1.0"), "ego.goal_tolerance_m"),
    "val_record_radius_negative": scenario(base("[output]\nrecord_radius_m = -1.0"), "output.record_radius_m"),
    "val_sa_cooling_over_1": scenario(base("[controllers.apf_sa]\nsa_cooling = 1.5"), "controllers.apf_sa.sa_cooling"),
    "val_sa_cooling_1": scenario(base("[controllers.apf_sa]\nsa_cooling = 1.0"), "controllers.apf_sa.sa_cooling"),
    "val_param_negative": scenario(base("[controllers.apf_sa]\nk_rep = -1.0"), "controllers.apf_sa.k_rep"),
    "val_ids_empty": scenario(base(ids="[]"), "ego"),
    "val_ids_duplicate": scenario(base(ids='["ego", "ego"]'), "ego.ids[1]"),
    "val_ego_not_in_routes": scenario(base(ids='["nobody"]'), "ego.ids[0]"),
    "val_controller": scenario(base(ego='controller = "magic"'), "ego.controller"),
    # SUMO's driver drives only on a route's lanes: an [arena]'s flock is off them
    "val_controller_sumo_in_arena": scenario(base("[arena]\nn_agents = 2", ego='controller = "sumo"'), "ego.controller"),
    "val_sensor": scenario(base(ego='sensor = "eyes"'), "ego.sensor"),
    "val_layer": scenario(base(ego='layers = ["traffic", "hope"]'), "ego.layers[1]"),
    "val_layer_twice": scenario(base(ego='layers = ["traffic", "traffic"]'), "ego.layers[1]"),
    "val_actuator": scenario(base(ego='actuator = "teleport"'), "ego.actuator"),
    "val_sensors_unknown": scenario(base("[sensors.lidar]\nrange_m = 1.0"), "sensors.lidar"),
    "val_sensors_truth_has_no_table": scenario(base("[sensors.truth]\nrange_m = 1.0"), "sensors.truth"),
    "val_layers_unknown": scenario(base("[layers.hope]\nx = 1"), "layers.hope"),
    "val_actuators_unknown": scenario(base("[actuators.teleport]\nx = 1"), "actuators.teleport"),
    "val_radar_fov": scenario(base("[sensors.radar]\nfov_deg = 270.0"), "sensors.radar"),
    "val_rear_axle_beyond_radius": scenario(base("[actuators.kinematic]\nrear_axle_m = 5.0"), "actuators.kinematic"),
    "val_relaxation_tau_zero": scenario(base("[actuators.relaxation]\ntau_s = 0.0"), "actuators.relaxation.tau_s"),
    "val_danger_time_levels": scenario(base("[layers.danger_time]\nbrake_s = 9.0"), "layers.danger_time"),
    # --- keys of the earlier layout: one line naming the new key --------------------------------
    "old_radar": scenario(base("[radar]\nrear = true"), "key 'radar' was renamed: use [sensors.radar]"),
    "old_safety": scenario(base("[safety]\nwarning_s = 4.0"), "key 'safety' was renamed: use [layers.danger_time]"),
    "old_rules": scenario(base("[rules]\nstop_margin_m = 2.0"), "key 'rules' was renamed: use [layers.traffic]"),
    "old_actuator": scenario(base("[actuator]\nmax_accel_mps2 = 2.0"),
                             "key 'actuator' was renamed: use [actuators.kinematic]"),
    "old_actuator_mode": scenario(base('[actuator]\nmode = "relaxation"\ntau_s = 0.5'),
                                  "key 'actuator.mode' was renamed: use ego.actuator"),
    "old_ego_rules": scenario(base(ego='rules = "none"'), "key 'ego.rules' was renamed: use ego.layers"),
    "old_ego_safety": scenario(base(ego='safety = "danger_time"'), "key 'ego.safety' was renamed: use ego.layers"),
    "old_set_radar": scenario(base(), "key 'radar' was renamed: use [sensors.radar]", extra_argv=["--set", "radar.rear=true"]),
    "old_set_ego_safety": scenario(base(), "key 'ego.safety' was renamed: use ego.layers",
                                   extra_argv=["--set", 'ego.safety="danger_time"']),
    "val_output_metric": scenario(base('[output]\nmetrics = ["happiness"]'), "output.metrics[0]"),
    "val_controllers_unknown": scenario(base("[controllers.magic]\nx = 1"), "controllers.magic"),
    "val_goal_three_numbers": scenario(base(ego="goal = [1.0, 2.0, 3.0]"), "ego.goal"),
    "val_goal_unknown_edge": scenario(base(ego='goal = "nowhere"'), "ego.goal"),
    "val_goal_off_net": scenario(base(ego="goal = [500.0, 300.0]"), "ego.goal"),
    "val_goal_huge": scenario(base(ego="goal = [1e308, 1e308]"), "ego.goal"),  # GEOS warned on the terminal
    "val_goals_unknown_ego": scenario(base('[ego.goals]\nnobody = "road"'), "ego.goals.nobody"),
    "val_scripted_stop_unknown_ego": scenario(
        base('[controllers.scripted]\nstop_after_m = {nobody = 10.0}', ego='controller = "scripted"'),
        "controllers.scripted.stop_after_m.nobody"),
    "val_obstacle_ids_duplicate": scenario(base(OBST.format(shape=SQ) + OBST.format(shape=SQ)), "obstacles[1].id"),
    "val_obstacle_two_points": scenario(base(OBST.format(shape="[[0.0, 0.0], [1.0, 1.0]]")), "obstacles[0]"),
    "val_obstacle_non_convex": scenario(base(OBST.format(
        shape="[[0.0, 0.0], [4.0, 0.0], [1.0, 1.0], [0.0, 4.0]]")), "obstacles[0].shape"),
    "val_obstacle_degenerate": scenario(base(OBST.format(shape="[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]")),
                                        "obstacles[0].shape"),
    "val_obstacle_self_crossing": scenario(base(OBST.format(
        shape="[[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]]")), "obstacles[0].shape"),
    "val_arena_length_zero": scenario(base("[arena]\nlength_m = 0.0\nn_agents = 2"), "arena.length_m"),
    "val_arena_size_zero": scenario(base("[arena]\nsize_m = 0.0"), "arena"),
    "val_arena_origin_three": scenario(base("[arena]\norigin = [0.0, 0.0, 0.0]"), "arena"),
    "val_arena_starts_count": scenario(base("[arena]\nn_agents = 2\nstarts = [[1.0, 1.0]]"), "arena.starts"),
    "val_arena_overfull": scenario(base("[arena]\nsize_m = 20.0\nn_agents = 500", ids="[]"), "arena.n_agents"),
    "val_random_obstacles_overfull": scenario(
        base("[random_obstacles]\nregion = [0.0, 0.0, 10.0, 10.0]\ncount = 500"), "random_obstacles.count"),
    # --- SUMO inputs: caught by loading them up front ---------------------------------------------
    "net_not_xml": scenario(base(net="{tmp}/n.net.xml"), "sim.net", files={"n.net.xml": "this is not XML\n"}),
    "net_truncated": scenario(base(net="{tmp}/n.net.xml"), "sim.net",
                              files={"n.net.xml": NET.read_text()[:len(NET.read_text()) // 2]}),
    "net_empty": scenario(base(net="{tmp}/n.net.xml"), "sim.net", files={"n.net.xml": ""}),
    "net_not_a_net": scenario(base(net="{tmp}/n.net.xml"), "sim.net", files={"n.net.xml": "<routes/>\n"}),
    "net_binary": scenario(base(net="{tmp}/n.net.xml"), "sim.net", files={"n.net.xml": b"\x89PNG\x00\xff"}),
    "net_is_folder": scenario(base(net="{tmp}"), "sim.net"),
    "routes_not_xml": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]", files={"r.rou.xml": "nope"}),
    "routes_truncated": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]",
                                 files={"r.rou.xml": ROUTES.read_text()[:300]}),
    "routes_empty": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]", files={"r.rou.xml": ""}),
    "routes_unknown_edge": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]", files={
        "r.rou.xml": '<routes><vehicle id="ego" depart="0"><route edges="road nowhere"/></vehicle></routes>'}),
    "routes_unknown_vtype": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]", files={
        "r.rou.xml": '<routes><trip id="ego" type="hovercraft" from="road" to="road" depart="0"/></routes>'}),
    "routes_unknown_route": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]", files={
        "r.rou.xml": '<routes><vehicle id="ego" route="nope" depart="0"/></routes>'}),
    "routes_depart_lane": scenario(base(routes=("{tmp}/r.rou.xml",)), "sim.routes[0]", files={
        "r.rou.xml": '<routes><trip id="ego" from="road" to="road" depart="1" departLane="7"/></routes>'}),
    "routes_unconnected": scenario(base(routes=("{tmp}/r.rou.xml",), net=ROOT / "nets" / "left_turn.net.xml"),
                                   "sim.routes[0]", files={
        "r.rou.xml": '<routes><vehicle id="ego" depart="0"><route edges="S2C N2C"/></vehicle></routes>'}),
    "additional_not_xml": scenario(base(sim='additional = ["{tmp}/a.add.xml"]'), "sim.additional[0]",
                                   files={"a.add.xml": "{{{"}),
    "additional_missing": scenario(base(sim='additional = ["missing.add.xml"]'), "sim.additional[0]"),
    "routes_missing": scenario(base(routes=("missing.rou.xml",)), "sim.routes[0]"),
    "net_missing": scenario(base(net="missing.net.xml"), "sim.net"),
    "ego_never_departs": scenario(base(routes=("{tmp}/r.rou.xml",)), "ego.ids[0]", files={
        "r.rou.xml": '<routes><trip id="ego" from="road" to="road" depart="60"/></routes>'}),
    # --- run: command line and file system -------------------------------------------------------
    "run_missing_scenario": _flag(["run", "{tmp}/none.toml"], ["{tmp}/none.toml"]),
    "run_scenario_is_folder": _flag(["run", "{tmp}"], ["{tmp}"]),
    "run_seed_negative": _flag(["run", SCN, "--seed", "-1", "--out", "{tmp}/o"], ["sim.seed"]),
    "run_seed_2_31": _flag(["run", SCN, "--seed", "2147483648", "--out", "{tmp}/o"], ["sim.seed"]),
    "run_seed_not_int": _flag(["run", SCN, "--seed", "one"], ["--seed"]),
    "run_unknown_flag": _flag(["run", SCN, "--sed", "1"], ["--sed"]),
    "run_controller": _flag(["run", SCN, "--controller", "magic", "--out", "{tmp}/o"], ["ego.controller"]),
    "run_controller_sumo_in_arena": _flag(["run", ARENA, "--set", 'ego.controller="sumo"', "--out", "{tmp}/o"],
                                          ["ego.controller"]),
    "run_set_no_equals": _flag(["run", SCN, "--set", "sim.seed"], ["--set", "sim.seed"]),
    "run_set_empty_key": _flag(["run", SCN, "--set", ".seed=1"], [".seed"]),
    "run_set_into_value": _flag(["run", SCN, "--set", "sim.net.x=1"], ["sim.net"]),
    "run_set_unknown_key": _flag(["run", SCN, "--set", "sim.nope=1"], ["sim.nope"]),
    "run_set_bad_value": _flag(["run", SCN, "--set", "sim.step_s=-1"], ["sim.step_s"]),
    "run_out_is_file": _flag(["run", SCN, "--out", SCN], ["--out", str(SCN)]),
    "run_out_read_only": _flag(["run", SCN, "--out", "/proc/sumo-avoid-out"], ["--out", "/proc/sumo-avoid-out"]),
    "run_no_scenario": _flag(["run"], ["scenario"]),
    # --- other commands' flags ---------------------------------------------------------------------
    "cli_no_command": _flag([], ["command"]),
    "cli_unknown_command": _flag(["fly"], ["fly"]),
    "keys_extra_argument": _flag(["keys", "extra"], ["extra"]),
    "controllers_unknown_flag": _flag(["controllers", "--all"], ["--all"]),
    "reproduce_what": _flag(["reproduce", "table5"], ["table5"]),
    "reproduce_seeds_zero": _flag(["reproduce", "table4", "--seeds", "0", "--out", "{tmp}/o"], ["--seeds"]),
    "reproduce_agents_negative": _flag(["reproduce", "table4", "--agents", "-1", "--out", "{tmp}/o"], ["--agents"]),
    "reproduce_duration_nan": _flag(["reproduce", "table4", "--duration", "nan", "--out", "{tmp}/o"], ["--duration"]),
    "reproduce_duration_huge": _flag(["reproduce", "table4", "--duration", "1e12", "--out", "{tmp}/o"],
                                     ["--duration"]),
    "reproduce_jobs_zero": _flag(["reproduce", "table4", "--jobs", "0", "--out", "{tmp}/o"], ["--jobs"]),
    "reproduce_bad_set": _flag(["reproduce", "table4", "--seeds", "1", "--agents", "3", "--duration", "1",
                                "--set", "controllers.flocking.nope=1", "--out", "{tmp}/o"],
                               ["controllers.flocking.nope"]),
    "reproduce_formation_runs": _flag(["reproduce", "formation", "--runs", "5-1", "--out", "{tmp}/o"], ["--runs"]),
    "reproduce_formation_workers_zero": _flag(["reproduce", "formation", "--runs", "1", "--workers", "0", "--out",
                                               "{tmp}/o"], ["--workers"]),
    "tune_controller": _flag(["tune", "apf", SCN, "--out", "{tmp}/o"], ["controller"]),
    "tune_nests": _flag(["tune", "formation", SCN, "--nests", "1", "--out", "{tmp}/o"], ["--nests"]),
    "tune_out_is_file": _flag(["tune", "formation", SCN, "--generations", "0", "--nests", "2", "--seeds", "1",
                               "--out", SCN], ["--out", str(SCN)]),
    "tune_ledger_not_sqlite": _flag(["tune", "formation", SCN, "--generations", "0", "--nests", "2", "--seeds", "1",
                                     "--out", "{tmp}/o", "--ledger", SCN], ["--ledger", str(SCN)]),
    "tune_flocking_bound_unknown": _flag(["tune", "flocking", ARENA, "--bound", "r0_rep", "1", "2", "--out", "{tmp}/o"],
                                         ["--bound", "r0_rep"]),
    "tune_flocking_bound_reversed": _flag(["tune", "flocking", ARENA, "--bound", "c_frict", "0.5", "0.1", "--out",
                                           "{tmp}/o"], ["--bound", "c_frict"]),
    "tune_flocking_out_is_file": _flag(["tune", "flocking", ARENA, "--out", SCN], ["--out", str(SCN)]),
    "tune_flocking_fresh_seeds_seen": _flag(["tune", "flocking", ARENA, "--first-seed", "1", "--out", "{tmp}/o"],
                                            ["--eval-first-seed"]),
    "tune_flocking_start_from_unknown": _flag(["tune", "flocking", ARENA, "--start-from", "paper", "--out", "{tmp}/o"],
                                              ["--start-from", "paper"]),
    "reproduce_table3_pop_size": _flag(["reproduce", "table3", "--pop-size", "1", "--out", "{tmp}/o"], ["--pop-size"]),
    "reproduce_table3_start_from_unknown": _flag(["reproduce", "table3", "--start-from", "best", "--out", "{tmp}/o"],
                                                 ["--start-from", "best"]),
    "reproduce_table3_out_is_file": _flag(["reproduce", "table3", "--out", SCN], ["--out", str(SCN)]),
    "reproduce_formation_out_is_file": _flag(["reproduce", "formation", "--runs", "1", "--out", SCN],
                                             ["--out", str(SCN)]),
    "reproduce_formation_tuned_not_tuned": _flag(["reproduce", "formation", "--runs", "1", "--out", "{tmp}/o",
                                                  "--tuned", SCN], [str(SCN), "controllers.formation"]),
    "run_out_under_a_file": _flag(["run", SCN, "--out", f"{SCN}/o"], ["--out", f"{SCN}/o"]),
    "run_set_unknown_arena_key": _flag(["run", ARENA, "--set", "arena.sizee_m=3", "--out", "{tmp}/o"],
                                       ["arena.sizee_m"]),
    "run_inject_crash_unknown": _flag(["run", SCN, "--inject-crash", "meteor", "--out", "{tmp}/o"],
                                      ["--inject-crash"]),
    "suite_ledger_is_folder": _flag(["suite", ROOT / "scenarios" / "suite.toml", "--ledger", "{tmp}"], ["--ledger"],
                                    family="suite"),
    # its CSV export (written beside it, suffix .csv) overwrote such a ledger after all the runs: refused up front
    "suite_ledger_named_csv": _flag(["suite", ROOT / "scenarios" / "suite.toml", "--ledger", "{tmp}/runs.csv"],
                                    ["--ledger", ".csv"], family="suite"),
    "batch_ledger_named_parquet": _flag(["batch", SCN, "--ledger", "{tmp}/runs.parquet"], ["--ledger", ".parquet"],
                                        family="batch"),
    "batch_keep_going_ledger_not_sqlite": _flag(["batch", SCN, "--keep-going", "--ledger", SCN], ["--ledger"],
                                                family="batch"),
    # --- batch ---------------------------------------------------------------------------------
    "batch_missing_scenario": _flag(["batch", "{tmp}/none.toml", "--ledger", "{tmp}/l/ledger.sqlite"],
                                    ["{tmp}/none.toml"], family="batch"),
    "batch_seeds_syntax": _flag(["batch", SCN, "--seeds", "1-x", "--ledger", "{tmp}/l.sqlite"], ["--seeds"],
                                family="batch"),
    "batch_seeds_reversed": _flag(["batch", SCN, "--seeds", "5-1", "--ledger", "{tmp}/l.sqlite"], ["--seeds"],
                                  family="batch"),
    "batch_seeds_huge_range": _flag(["batch", SCN, "--seeds", "0-1000000000", "--ledger", "{tmp}/l.sqlite"],
                                    ["--seeds"], family="batch"),
    "batch_seeds_2_31": _flag(["batch", SCN, "--seeds", "2147483648", "--ledger", "{tmp}/l.sqlite"], ["--seeds"],
                              family="batch"),
    "batch_timeout_nan": _flag(["batch", SCN, "--timeout", "nan", "--ledger", "{tmp}/l.sqlite"], ["--timeout"],
                               family="batch"),
    "batch_timeout_negative": _flag(["batch", SCN, "--timeout", "-1", "--ledger", "{tmp}/l.sqlite"], ["--timeout"],
                                    family="batch"),
    "batch_workers_zero": _flag(["batch", SCN, "--workers", "0", "--ledger", "{tmp}/l.sqlite"], ["--workers"],
                                family="batch"),
    "batch_start": _flag(["batch", SCN, "--start", "teleport", "--ledger", "{tmp}/l.sqlite"], ["--start"],
                         family="batch"),
    "batch_old_key": _flag(["batch", SCN, "--set", "radar.rear=true", "--ledger", "{tmp}/l.sqlite"],
                           [str(SCN), "key 'radar' was renamed: use [sensors.radar]"], family="batch"),
    "batch_ledger_is_folder": _flag(["batch", SCN, "--ledger", "{tmp}"], ["--ledger", "{tmp}"], family="batch"),
    "batch_ledger_not_sqlite": _flag(["batch", SCN, "--ledger", SCN], ["--ledger", str(SCN)], family="batch"),
    "batch_controller": _flag(["batch", SCN, "--controller", "magic", "--ledger", "{tmp}/l.sqlite"],
                              ["ego.controller"], family="batch"),
}


def _batch_file(text, key, files=None, argv=()) -> Case:
    def make(tmp):
        for name, content in (files or {}).items():
            (tmp / name).write_text(content)
        p = tmp / "b.toml"
        p.write_text(text.replace("{scn}", str(SCN)))
        return Call(["batch", p, *argv], (str(p), key), cwd=tmp)
    return Case("batch-file", make)


def _suite_file(text, key, argv=(), names=()) -> Case:
    def make(tmp):
        p = tmp / "s.suite.toml"
        p.write_text(text.replace("{scn}", str(SCN)))
        return Call(["suite", p, *[a.replace("{tmp}", str(tmp)) for a in argv]],
                    (str(p) if key.startswith(("entry", "<", "defaults")) else "", key, *names), cwd=tmp)
    return Case("suite", make)


RUNS = '[[runs]]\nscenario = "{scn}"\nseeds = "1"\n'
SUITE = ('[[entry]]\nname = "a"\nscenario = "{scn}"\nseeds = "1"\ncriteria = ["collisions == 0"]\n'
         'set = ["sim.duration_s=2.0", "output.plots=false"]\n')
CASES.update({
    "batchfile_unknown_key": _batch_file(RUNS + "colour = 1\n", "runs[0].colour"),
    "batchfile_no_runs": _batch_file("workers = 2\nruns = []\n", "runs"),
    "batchfile_seeds": _batch_file(RUNS.replace('"1"', '"x"'), "runs[0].seeds"),
    "batchfile_grid": _batch_file(RUNS + "grid = {\"sim.seed\" = 3}\n", "runs[0].grid.sim.seed"),
    "batchfile_crash": _batch_file(RUNS + 'inject_crash = "meteor"\n', "runs[0].inject_crash"),
    "batchfile_workers": _batch_file("workers = 0\n" + RUNS, "workers"),
    "batchfile_timeout": _batch_file("timeout_s = nan\n" + RUNS, "timeout_s"),
    "batchfile_with_seeds_flag": _batch_file(RUNS, "--seeds", argv=("--seeds", "1-2")),
    "batchfile_scenario_missing": _batch_file(RUNS.replace("{scn}", "none.toml"), "runs[0].scenario"),
    "suite_scenario_missing": _suite_file(SUITE.replace("{scn}", "none.toml"), "entry[0].scenario"),
    "batchfile_syntax": _batch_file("[[runs]\n", "<syntax>"),
    "suite_syntax": _suite_file("[[entry]\n", "<syntax>"),
    "suite_no_entry": _suite_file("[defaults]\nseeds = \"1\"\n", "entry"),
    "suite_criterion_syntax": _suite_file(SUITE.replace("collisions == 0", "collisions is zero"),
                                          "entry[0].criteria[0]"),
    "suite_criterion_unknown_metric": _suite_file(SUITE.replace("collisions == 0", "happiness >= 1"),
                                                  "entry[0].criteria[0]", names=("'happiness'", "nearest: ")),
    "suite_criterion_typo": _suite_file(SUITE.replace("collisions == 0", "min_gap_mm_min >= 0.5"),
                                        "entry[0].criteria[0]", names=("nearest: min_gap_m_min",)),
    "suite_criterion_nested_metric": _suite_file(SUITE.replace("collisions == 0", "collision_events == 0"),
                                                 "entry[0].criteria[0]", names=("'collision_events' is a list",)),
    "suite_criterion_text_metric": _suite_file(SUITE.replace("collisions == 0", "controller == 1"),
                                               "entry[0].criteria[0]", names=("'controller' is text",)),
    "suite_criterion_other_controllers_metric": _suite_file(  # APF-SA's counter, the entry drives plain APF
        SUITE.replace("collisions == 0", "sa_escapes_max <= 2") + 'controller = "apf"\n', "entry[0].criteria[0]"),
    "suite_criterion_second_entry": _suite_file(SUITE + SUITE.replace('"a"', '"b"').replace("collisions == 0", "mu >= 0"),
                                                "entry[1].criteria[0]"),
    "suite_criterion_ratio_in_an_arena": _suite_file(  # SUMO's driver, its baseline, cannot drive an arena's flock
        SUITE.replace("{scn}", str(ARENA)).replace("collisions == 0", "travel_time_ratio_median <= 1.5"),
        "entry[0].criteria[0]", names=("'travel_time_ratio_median'",)),
    "suite_duplicate_names": _suite_file(SUITE + SUITE, "entry[1].name"),
    "suite_no_seeds": _suite_file(SUITE.replace('seeds = "1"\n', ""), "entry[0].seeds"),
    "suite_seeds_flag": _suite_file(SUITE, "--seeds", argv=("--seeds", "x")),
    "suite_timeout_nan": _suite_file(SUITE, "--timeout", argv=("--timeout", "nan")),
    "suite_workers_zero": _suite_file(SUITE, "--workers", argv=("--workers", "0")),
    "suite_junit_is_folder": _suite_file(SUITE, "--junit", argv=("--junit", "{tmp}")),
    "suite_junit_under_a_file": _suite_file(SUITE, "--junit", argv=("--junit", f"{SCN}/suite.xml")),
    "suite_controller": _suite_file(SUITE + 'controller = "magic"\n', "ego.controller"),
})


def _report(setup, argv, names) -> Case:
    """``sumo-avoid report SRC --out {tmp}/r.html ...`` after ``setup(tmp)`` made the input."""
    def make(tmp):
        src = setup(tmp)
        args = [a.replace("{tmp}", str(tmp)) for a in argv]
        return Call(["report", src, *args], tuple(n.replace("{tmp}", str(tmp)) for n in names), cwd=tmp)
    return Case("report", make)


def _runs_dir(tmp, text="{", ledger=False):
    d = tmp / "study" / "r1"
    d.mkdir(parents=True)
    (d / "metrics.json").write_text(text)
    return tmp / "study"


def _sqlite(tmp, sql="CREATE TABLE other (x INTEGER)"):
    p = tmp / "x.sqlite"
    with sqlite3.connect(p) as con:
        con.execute(sql)
    con.close()
    return p


def _text(tmp):
    (tmp / "notes.sqlite").write_text("not a database\n" * 20)
    return tmp / "notes.sqlite"


def _csv_export(tmp):
    (tmp / "runs.csv").write_text("key,scenario,seed\nk1,s,1\n")
    return tmp / "runs.csv"


_GOOD_RUN = '{"scenario": "s", "controller": "c", "seed": 1, "collisions": 0}'
CASES.update({
    "report_missing": _report(lambda t: t / "none.sqlite", ["--out", "{tmp}/r.html"], ["{tmp}/none.sqlite"]),
    "report_empty_folder": _report(lambda t: t, ["--out", "{tmp}/r.html"], ["{tmp}"]),
    "report_text_file": _report(_text, ["--out", "{tmp}/r.html"], ["notes.sqlite"]),
    # a batch's CSV export given where its ledger belongs: read as a ledger and refused (not as a name to write)
    "report_csv_export": _report(_csv_export, ["--out", "{tmp}/r.html"], ["runs.csv", "SQLite"]),
    "report_sqlite_not_ledger": _report(_sqlite, ["--out", "{tmp}/r.html"], ["x.sqlite"]),
    "report_metrics_corrupt": _report(_runs_dir, ["--out", "{tmp}/r.html"], ["metrics.json"]),
    "report_metrics_not_object": _report(lambda t: _runs_dir(t, "[1, 2]"), ["--out", "{tmp}/r.html"],
                                         ["metrics.json"]),
    "report_out_is_folder": _report(lambda t: _runs_dir(t, _GOOD_RUN), ["--out", "{tmp}"], ["--out"]),
    "report_md_is_folder": _report(lambda t: _runs_dir(t, _GOOD_RUN), ["--out", "{tmp}/r.html", "--md", "{tmp}"],
                                   ["--md"]),
    "report_md_under_a_file": _report(lambda t: _runs_dir(t, _GOOD_RUN),
                                      ["--out", "{tmp}/r.html", "--md", f"{SCN}/r.md"], ["--md"]),
    "report_csv_is_folder": _report(lambda t: _runs_dir(t, _GOOD_RUN), ["--out", "{tmp}/r.html", "--csv", "{tmp}"],
                                    ["--csv"]),
    "report_run_unknown": _report(lambda t: _runs_dir(t, _GOOD_RUN), ["--out", "{tmp}/r.html", "--run", "zzz"],
                                  ["--run"]),
    "report_out_missing_flag": _report(lambda t: _runs_dir(t, _GOOD_RUN), [], ["--out"]),
})



def _replay(argv, names, setup=lambda t: t) -> Case:
    """``sumo-avoid replay SRC ...`` (``{tmp}`` is the folder) after ``setup(tmp)`` made SRC."""
    def make(tmp):
        src = setup(tmp)
        return Call(["replay", src, *[a.replace("{tmp}", str(tmp)) for a in argv]],
                    tuple(n.replace("{tmp}", str(tmp)) for n in names), cwd=tmp)
    return Case("replay", make)


def _half_run(tmp):  # a run folder without its trajectories
    d = tmp / "run"
    d.mkdir()
    (d / "metrics.json").write_text(_GOOD_RUN)
    return d


CASES.update({
    "replay_missing_folder": _replay([], ["{tmp}/none", "RUN_DIR"], lambda t: t / "none"),
    "replay_not_a_run": _replay([], ["run", "trajectories.csv"], _half_run),
    "replay_video_suffix": _replay(["--video", "{tmp}/v.avi"], ["--video", ".mp4"]),
    "replay_video_is_folder": _replay(["--video", "{tmp}"], ["--video"]),
    "replay_video_under_a_file": _replay(["--video", f"{SCN}/v.mp4"], ["--video"]),
    "replay_from_after_to": _replay(["--from", "5", "--to", "2"], ["--to"]),
    "replay_speed_zero": _replay(["--speed", "0"], ["--speed"]),
    "replay_fps_nan": _replay(["--fps", "nan"], ["--fps"]),
    "replay_screenshot_with_video": _replay(["--video", "{tmp}/v.mp4", "--screenshot", "{tmp}/s.png"],
                                            ["--screenshot"]),
    "run_video_suffix": Case("run", lambda t: Call(["run", SCN, "--out", t / "o", "--video", t / "v.avi"], ("--video",))),
    "report_one_run_md": _report(lambda t: _runs_dir(t, _GOOD_RUN) / "r1", ["--md", "{tmp}/s.md"], ["--md"]),
})

# cases that fail today, with the cause (strict: a case that starts passing must leave this list)
XFAIL: dict[str, str] = {}


def _params():
    for name in sorted(CASES):
        marks = [pytest.mark.xfail(strict=True, reason=XFAIL[name]), pytest.mark.sumo] if name in XFAIL else []
        yield pytest.param(name, marks=marks + ([pytest.mark.sumo] if CASES[name].sub else []), id=name)


@pytest.mark.parametrize("name", list(_params()))
def test_bad_input(name, tmp_path):
    check(CASES[name], tmp_path)


def test_a_goal_far_off_the_net_is_one_line_without_a_warning(tmp_path):
    """A Python warning would print on the terminal before our line (the corpus' in-process runs
    do not see warnings: pytest collects them)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = cli_in_process("run", ROOT / "scenarios" / "left_turn.toml", "--set", "ego.goal=[1e308, 1e308]",
                             "--out", tmp_path / "o")
    assert res.returncode == 2 and "ego.goal" in res.stderr and res.stderr.count("\n") == 1
    assert not (tmp_path / "o").exists()
