"""The test suite's time, two commits back to back, as CI runs it: ``.ci/run`` on a clean clone.

    python benchmarks/suite_time.py OLD NEW [--pairs 2] [--repo .]

For each pair, OLD and NEW are cloned afresh from ``--repo`` into a temporary folder and their
``.ci/run`` (a fresh venv, ``pip install -e '.[test]'``, README's test command) runs one after the
other; the order alternates between pairs (OLD first, then NEW first, ...), because these shared
2-core machines change speed from one minute to the next (the same commit measured 173 s and 234 s
of tests within an hour). Printed per run: pytest's own line (tests and seconds), the wall time of
the whole ``.ci/run`` and the CPU time of it and its children; then per pair NEW / OLD for pytest's
seconds and for the wall time. Only ratios within a pair compare like with like.
"""
from __future__ import annotations

import argparse
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LINE = re.compile(r"(\d+) passed.* in ([\d.]+)s")


def run_ci(repo: Path, commit: str, tmp: Path) -> dict:
    """Clone ``commit`` into ``tmp`` and run its .ci/run; pytest's line, wall and CPU seconds."""
    subprocess.run(["git", "clone", "-q", str(repo), str(tmp)], check=True)
    subprocess.run(["git", "-C", str(tmp), "checkout", "-q", commit], check=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([str(tmp / ".ci" / "run")], cwd=tmp, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    found = LINE.findall(proc.stdout)
    if proc.returncode != 0 or not found:
        tail = (proc.stdout + proc.stderr).strip().splitlines()[-3:]
        raise SystemExit(f"suite_time: error: .ci/run of {commit} exited {proc.returncode}: {' | '.join(tail)}")
    tests, secs = found[-1]
    return {"commit": commit, "tests": int(tests), "pytest_s": float(secs), "wall_s": wall, "cpu_s": cpu}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--pairs", type=int, default=2)
    ap.add_argument("--repo", type=Path, default=Path(__file__).resolve().parents[1])
    a = ap.parse_args(argv)
    if a.pairs < 1:
        print("suite_time: error: --pairs must be at least 1", file=sys.stderr)
        return 2
    if subprocess.run(["git", "-C", str(a.repo), "rev-parse", "--git-dir"], capture_output=True).returncode != 0:
        print(f"suite_time: error: --repo {a.repo} is not a git repository", file=sys.stderr)
        return 2
    for c in (a.old, a.new):
        if subprocess.run(["git", "-C", str(a.repo), "cat-file", "-e", f"{c}^{{commit}}"],
                          capture_output=True).returncode != 0:
            print(f"suite_time: error: {c!r} is not a commit of {a.repo}", file=sys.stderr)
            return 2
    ratios = []
    for p in range(a.pairs):
        order = (a.old, a.new) if p % 2 == 0 else (a.new, a.old)
        res = {}
        for c in order:
            with tempfile.TemporaryDirectory(prefix="suite-time-") as d:
                r = run_ci(a.repo, c, Path(d) / "clone")
            res[c] = r
            print(f"pair {p + 1}  {c:>12}  {r['tests']:4d} tests  pytest {r['pytest_s']:6.1f} s  "
                  f"wall {r['wall_s']:6.1f} s  cpu {r['cpu_s']:6.1f} s", flush=True)
        o, n = res[a.old], res[a.new]
        ratios.append((n["pytest_s"] / o["pytest_s"], n["wall_s"] / o["wall_s"]))
        print(f"pair {p + 1}  new/old  pytest {ratios[-1][0]:.3f}  wall {ratios[-1][1]:.3f}", flush=True)
    ps, ws = sorted(r[0] for r in ratios), sorted(r[1] for r in ratios)
    print(f"new/old over {a.pairs} pairs: pytest {ps[0]:.3f}..{ps[-1]:.3f}, wall {ws[0]:.3f}..{ws[-1]:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
