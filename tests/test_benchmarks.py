"""The radar benchmark's machinery on a tiny traffic (its timings are not asserted: speed is
measured by running the benchmark, not in tests). Real libsumo, real nets."""
import re
import subprocess
import sys

import pytest
from conftest import ROOT

LAST = re.compile(r"^plugin_s=(\d+\.\d\d) plain_s=(\d+\.\d\d) ratio=(\d+\.\d\d)$")


@pytest.mark.parametrize("net", ["single", "segments"])
def test_radar_benchmark_takes_turns_and_prints_its_last_line(net):
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "radar.py"), "--vehicles", "150", "--egos", "5",
                          "--duration", "1", "--chunk", "3", "--net", net],
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    m = LAST.match(lines[-1])
    assert m, lines[-1]
    plugin_s, plain_s, ratio = map(float, m.groups())
    assert plugin_s > 0 and plain_s > 0
    # the ratio is of the unrounded times: consistent with the printed ones within their rounding
    assert (plugin_s - 0.005) / (plain_s + 0.005) - 0.005 <= ratio <= (plugin_s + 0.005) / (plain_s - 0.005) + 0.005
    # both sides ran all 10 steps and the plug-in drove its 5 egos with the radar in the loop
    assert "egos 5  steps 10" in out.stdout and f"net {net}" in out.stdout
    assert re.search(r"paired turns \(3, same steps\): plug-in / plain median \d+\.\d{3}", out.stdout), out.stdout
    assert "steps: plain 10/10  plugin 10/10" in out.stderr


def test_benchmark_turns_alternate_between_two_processes():
    """The baton: with chunk 2, the sides' step counters interleave (neither runs ahead by more
    than one chunk while the other still has steps to do)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import multiprocessing as mp

    import radar as bench

    ctx = mp.get_context("fork")
    sems = (ctx.Semaphore(0), ctx.Semaphore(0))
    done = ctx.Array("i", 2)
    log, k = ctx.Array("i", 10), ctx.Value("i", 0)  # written only by the side holding the baton

    def side(me, n):
        t = bench.Turns(sems[me], sems[1 - me], done, me, 2, ctx.Value("i", 0))
        t.wait_turn()
        for _ in range(n):
            log[k.value] = me
            k.value += 1
            t.stepped()
        t.finish()

    procs = [ctx.Process(target=side, args=(k, n)) for k, n in ((0, 6), (1, 4))]
    for p in procs:
        p.start()
    sems[0].release()
    for p in procs:
        p.join(timeout=30)
    assert list(log) == [0, 0, 1, 1, 0, 0, 1, 1, 0, 0]


def test_sumo_step_benchmark_compares_two_ways_of_driving_the_egos():
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "sumo_step.py"), "setspeed", "move",
                          "--steps", "6"], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    m = re.match(r"^setspeed_s=(\d+\.\d\d) move_s=(\d+\.\d\d) ratio=(\d+\.\d\d\d)$", out.stdout.strip().splitlines()[-1])
    assert m, out.stdout
    assert float(m.group(1)) > 0 and float(m.group(2)) > 0
    assert "steps: setspeed 6/6  move 6/6" in out.stderr


def test_planner_benchmark_replays_every_plan_of_a_run():
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "planner.py"), "--seeds", "1", "--repeat", "1"], check=False,
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    m = re.match(r"^plans=(\d+) median_ms=(\d+\.\d) p95_ms=(\d+\.\d) max_ms=(\d+\.\d)$", lines[-1])
    assert m, lines[-1]
    n = int(m.group(1))
    assert n >= 2 and 0 < float(m.group(2)) <= float(m.group(3)) <= float(m.group(4))
    assert re.match(rf"^seed 1: {n} plans, in-run median", lines[0]) and lines[-3].startswith(f"in-run:   plans={n} ")
    assert lines[-2].startswith(f"cpu:      plans={n} ")


def test_suite_time_reads_pytests_line_and_refuses_what_is_not_a_commit(capsys, tmp_path):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import suite_time
    finally:
        sys.path.pop(0)
    assert suite_time.LINE.findall("862 passed, 1 warning in 149.71s (0:02:29)") == [("862", "149.71")]
    assert suite_time.main(["no-such-commit", "HEAD"]) == 2
    assert suite_time.main(["HEAD", "HEAD", "--pairs", "0"]) == 2
    assert suite_time.main(["HEAD", "HEAD", "--repo", str(tmp_path)]) == 2  # a folder that is no repository
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "'no-such-commit' is not a commit" in err and "is not a git repository" in err


def _record(root, metrics: dict, rows: list[list], table4_cell: str):
    """A hand-made record of same_behaviour.py: one run (metrics.json, trajectories.csv) and table4."""
    import json

    run = root / "runs" / "x-s1"
    run.mkdir(parents=True)
    (run / "metrics.json").write_text(json.dumps(metrics, indent=2, sort_keys=True) + "\n")
    (run / "trajectories.csv").write_text("\n".join(",".join(map(str, r)) for r in rows) + "\n")
    (root / "table4").mkdir()
    (root / "table4" / "table4.csv").write_text(f"v,mu\n4,{table4_cell}\n")
    jobs = [{"name": "table4", "out": "table4", "exit_code": 0}, {"name": "x-s1", "out": "runs/x-s1", "exit_code": 0}]
    (root / "record.json").write_text(json.dumps({"code_commit": "abc", "jobs": jobs}))
    return root


def test_same_behaviour_compare_within_a_relative_tolerance(tmp_path, capsys):
    """Records of two machines: byte-identical by default; with --tolerance REL, numbers within REL
    relative pass and the largest difference is printed; a changed text or column never passes."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        import same_behaviour as sb
    finally:
        sys.path.pop(0)
    head = ["step", "id", "x", "y"]
    base = _record(tmp_path / "base", {"min_gap_m": 1.25, "n": 3, "ok": True},
                   [head, [0, "ego", 1234.5, -0.75], [1, "ego", 1240.0, -0.5]], "0.8125")
    # x off by 1e-13 relative, min_gap_m by 3e-13, table4's mu by 5e-13 (table4 alone allows 1e-12)
    new = _record(tmp_path / "new", {"min_gap_m": 1.25 * (1 + 3e-13), "n": 3, "ok": True},
                  [head, [0, "ego", 1234.5 * (1 + 1e-13), -0.75], [1, "ego", 1240.0, -0.5]], repr(0.8125 * (1 + 5e-13)))
    same = _record(tmp_path / "same", {"min_gap_m": 1.25, "n": 3, "ok": True},
                   [head, [0, "ego", 1234.5, -0.75], [1, "ego", 1240.0, -0.5]], "0.8125")

    def compare(b, n, *opts):
        code = sb.main(["compare", str(b), str(n), *opts])
        return code, capsys.readouterr().out.strip().splitlines()

    assert compare(base, same)[0] == 0
    code, out = compare(base, new)  # default: byte-identical, but for table4's 1e-12
    assert code == 1 and any(line.startswith("DIFFERS runs/x-s1/metrics.json") for line in out)
    assert any(line.startswith("within 1e-12 (allowed) table4/table4.csv") for line in out)
    code, out = compare(base, new, "--tolerance", "1e-12")
    assert code == 0, out
    assert any(line.startswith("within 1e-12 (allowed) runs/x-s1/trajectories.csv: largest relative difference 1e-13")
               for line in out), out
    assert out[-1] == "identical: 0 of 3 files; largest relative difference: 5e-13 (3 file(s) within the tolerance 1e-12)"
    code, out = compare(base, new, "--tolerance", "2e-13")  # metrics.json's 3e-13 is beyond it
    assert code == 1 and any(line.startswith("DIFFERS runs/x-s1/metrics.json") for line in out)
    assert any(line.startswith("within 2e-13 (allowed) runs/x-s1/trajectories.csv") for line in out)
    assert any(line.startswith("within 1e-12 (allowed) table4/table4.csv") for line in out)  # never below 1e-12
    # a changed id or a changed key is no rounding: beyond any tolerance
    text = _record(tmp_path / "text", {"min_gap_m": 1.25, "n": 3, "ok": False},
                   [head, [0, "car", 1234.5, -0.75], [1, "ego", 1240.0, -0.5]], "0.8125")
    code, out = compare(base, text, "--tolerance", "0.5")
    assert code == 1 and "largest relative difference: inf" in out[-1]
    assert any(line.startswith("DIFFERS runs/x-s1/trajectories.csv") and "id (inf)" in line for line in out)
    with pytest.raises(SystemExit):
        sb.main(["compare", str(base), str(new), "--tolerance", "-1"])


def test_replay_record_benchmark_prints_its_share():
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "replay_record.py"), "--scenario", "crash_straight",
                          "--repeat", "2"], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert re.fullmatch(r"max_share=\d\.\d{5}", out.stdout.strip().splitlines()[-1])
    assert "crash_straight: run " in out.stdout


def test_arena_benchmark_replays_the_run_taking_turns():
    """``benchmarks/arena.py --turns``: the run again and the replay of its recorded poses as two processes taking
    turns; both sides step as often (the spawn step and 19 more), and the last line is the ratio's."""
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "arena.py"), "--agents", "5", "--duration", "4",
                          "--repeat", "1", "--skip-neighbours", "--turns", "--chunk", "3"],
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    m = re.match(r"^wall_s=(\d+\.\d\d) plain_s=(\d+\.\d\d) ratio=(\d+\.\d\d)$", lines[-1])
    assert m, lines[-1]
    assert float(m.group(1)) > 0 and float(m.group(2)) > 0
    assert "arena run: N=5 4 s, 20 steps" in out.stdout
    assert re.search(r"paired turns \(6, same steps\): plug-in / plain median \d+\.\d{3}", out.stdout), out.stdout
    assert "steps: plain 20/20  plugin 20/20" in out.stderr


@pytest.mark.parametrize("script", ["warmup.py", "replay_record.py"])
def test_a_benchmark_given_a_scenario_that_is_not_there_says_so_in_one_line(script):
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), "--scenario", "no_such_scenario"],
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr.count("\n") == 1 and "no_such_scenario.toml" in out.stderr and "Traceback" not in out.stderr


def test_warmup_benchmark_compares_the_two_readings_and_prints_its_ratio():
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "warmup.py"), "--scenario", "streets/van_bike_lane",
                          "--end", "20"], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert "the same" in lines[0] and re.fullmatch(r"ratio=\d+\.\d{3}", lines[-1]), out.stdout


@pytest.mark.parametrize("script", ["arena.py", "planner.py", "radar.py", "replay_record.py", "warmup.py"])
def test_a_benchmark_asked_for_no_repeat_says_so_before_it_runs(script):
    """``--repeat 0`` left nothing to take a median of (a StatisticsError traceback after the runs)."""
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), "--repeat", "0"],
                         capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert out.returncode == 2 and out.stdout == "" and "Traceback" not in out.stderr
    assert out.stderr.strip().splitlines()[-1].endswith("--repeat: invalid positive integer value: '0'")
