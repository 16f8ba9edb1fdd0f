"""Prove that a refactor did not change behaviour: record every scenario's outputs, compare two records.

Usage::

    # record the outputs of the code in DIR (default: the checkout this script lives in)
    python benchmarks/same_behaviour.py record OUT_DIR [--code DIR] [--seeds 1-3] [--workers 2] [--only NAME ...]
                                             [--suite FILE ...] [--no-singles]

    # compare two records; exit 0 = same behaviour, 1 = not
    python benchmarks/same_behaviour.py compare BASE_DIR NEW_DIR [--only NAME ...] [--tolerance REL]

``record`` runs, for every single-run scenario ``DIR/scenarios/*.toml`` (a file with a ``[sim]``
table; ``suite.toml``, a suite of entries, is skipped) and every seed::

    sys.executable -m sumo_avoid.cli run scenarios/NAME.toml --seed N --out OUT_DIR/runs/NAME-sN --no-plots --quiet

and once::

    sys.executable -m sumo_avoid.cli reproduce table4 --seeds 3 --out OUT_DIR/table4 --jobs 1

each as a subprocess with ``cwd=DIR`` and ``PYTHONPATH=DIR`` (so DIR's ``sumo_avoid`` is imported,
not the editable install; the record checks this and writes the imported path to its manifest),
``OMP/OPENBLAS/MKL_NUM_THREADS=1`` (as the project's batch workers) and ``PYTHONHASHSEED=0``.
Table 4 runs with its defaults (N = 100, 600 s) over 3 seeds; ``--jobs 1`` only keeps it to one of
the ``--workers`` slots (its outputs do not depend on it). ``--suite FILE`` (repeatable, relative to DIR,
e.g. ``scenarios/streets.toml``) adds every entry of a scenario suite, at each seed, run as the suite
runs it: its scenario (relative to the suite file), ``--controller`` and every ``--set`` of the suite's
``[defaults]`` and the entry, under the job name ``SUITE.ENTRY-sN`` (``SUITE`` the file's stem, ``ENTRY``
the entry's name with ``/`` and spaces as ``_``); ``--no-singles`` leaves out the single-run
scenarios and table4. ``--only NAME`` (repeatable) restricts the
record to scenario NAME (file stem) and/or ``table4``. Jobs run ``--workers`` at a time. Every job's
stdout/stderr goes to ``OUT_DIR/logs/JOB.log``; ``OUT_DIR/record.json`` holds the code checkout (its
git commit and whether its tracked files were modified), the imported ``sumo_avoid`` path, the
numpy and numba versions and the SIMD kernels numpy dispatches on the machine (``build``), the
environment, and per job the command, exit code and wall time. A job that exits non-zero is an
error: ``record`` reports it and exits 1 (the record is kept, and ``compare`` counts the job as
different).

What counts as "same" (``compare``):

* per scenario run: ``metrics.json``, ``trajectories.csv`` and ``detections.csv`` (when either
  record has it) must be **byte-identical**. ``timings.json``, ``sumo.log`` and plots are not
  compared (wall clock, SUMO's log text).
* ``table4/``: every ``*.csv`` and ``*.json`` (``table4.csv``, ``runs/v*_s*.json``) except any
  ``timings.json``. Wall-clock fields (``wall_s``, see ``WALL_CLOCK_KEYS``) are removed from JSON
  files before comparing; the rest must be identical, except that order-parameter values may
  differ by less than ``1e-12`` relative (reported, allowed). ``table4.md`` (it holds the command
  line with the output path, and wall time) and the figures are not compared.
* every job of either record must have exit code 0, and both records must hold the same jobs
  (with ``--only``, just the named ones).
* ``--tolerance REL`` (default 0: byte-identical, as above) is for two records made on different
  machines or numpy / numba builds, where the same code rounds differently in the last bits (numpy
  picks its SIMD kernels by CPU; a compiler may fuse a multiply-add): a file that is not
  byte-identical is then still the same when it differs only in numbers, each within ``REL``
  relative (table4's files: within the larger of ``REL`` and ``1e-12``). Anything else (a key,
  column, row or text that differs) is never within a tolerance. On one machine with one build,
  compare without it: the same code gives the same bytes.

When a file is not identical, it is parsed (JSON / CSV) and the line printed for it names the
keys or columns that differ and the largest relative difference of their numeric values
(``|a - b| / max(|a|, |b|)``; a value that is numeric on one side only, a NaN against a number, or
a missing row/key counts as ``inf``). The last line is ``identical: K of N files; largest relative
difference: X`` (with ``--tolerance``, also how many files were within it).
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import pathlib
import platform
import re
import subprocess
import sys
import time

import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]
RUN_FILES = ("metrics.json", "trajectories.csv", "detections.csv")
TABLE4 = "table4"
TABLE4_REL_TOL = 1e-12  # allowed only for table4's order-parameter files
WALL_CLOCK_KEYS = frozenset({"wall_s", "overhead_s", "started_at", "ended_at", "import_s"})
NEVER_COMPARED = frozenset({"timings.json"})
PROBE = ("import json, numba, numpy, sumo_avoid; from numpy._core._multiarray_umath import __cpu_features__ as f, "
         "__cpu_dispatch__ as d; print(json.dumps({'sumo_avoid': sumo_avoid.__file__, 'numpy': numpy.__version__, "
         "'numba': numba.__version__, 'numpy_dispatch': [k for k in d if f.get(k)]}))")
CHILD_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "PYTHONHASHSEED": "0"}


# ----------------------------------------------------------------------------------------- record
def parse_seeds(text: str) -> list[int]:
    """'1-3' -> [1, 2, 3]; '1,4,7-8' -> [1, 4, 7, 8]."""
    seeds: list[int] = []
    for part in text.split(","):
        part = part.strip()
        if re.fullmatch(r"\d+-\d+", part):
            a, b = map(int, part.split("-"))
            if b < a:
                raise argparse.ArgumentTypeError(f"empty seed range {part!r}")
            seeds.extend(range(a, b + 1))
        elif re.fullmatch(r"\d+", part):
            seeds.append(int(part))
        else:
            raise argparse.ArgumentTypeError(f"bad seeds {text!r} (e.g. 1-3 or 1,2,5)")
    return sorted(set(seeds))


def single_run_scenarios(code: pathlib.Path) -> tuple[list[pathlib.Path], list[tuple[str, str]]]:
    """The scenario files of a checkout that describe one run ([sim] table, no suite entries)."""
    keep, skipped = [], []
    for p in sorted((code / "scenarios").glob("*.toml")):
        try:
            doc = tomllib.loads(p.read_text())
        except tomllib.TOMLDecodeError as e:
            skipped.append((p.name, f"not valid TOML: {e}"))
            continue
        if "entry" in doc or "defaults" in doc:
            skipped.append((p.name, "a suite file ([[entry]] list), not a scenario"))
        elif not isinstance(doc.get("sim"), dict):
            skipped.append((p.name, "no [sim] table"))
        else:
            keep.append(p)
    return keep, skipped


def suite_entries(code: pathlib.Path, suite: str) -> list[tuple[str, list[str]]]:
    """(job base name, ``run`` arguments without --seed / --out) of every entry of a suite file."""
    path = code / suite
    doc = tomllib.loads(path.read_text())
    defaults = doc.get("defaults", {})
    out = []
    for e in doc.get("entry", []):
        name = f"{path.stem}.{re.sub(r'[/ ()]+', '_', e['name']).strip('_')}"
        args = [str((path.parent / e["scenario"]).relative_to(code))]
        if e.get("controller"):
            args += ["--controller", e["controller"]]
        for kv in [*defaults.get("set", []), *e.get("set", [])]:
            args += ["--set", kv]
        out.append((name, args))
    return out


def child_env(code: pathlib.Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(CHILD_ENV, PYTHONPATH=str(code))
    return env


def _git(code: pathlib.Path, *args: str) -> str | None:
    try:
        return subprocess.run(["git", "-C", str(code), *args], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def _run_job(job: dict, code: str, env: dict, log: str) -> dict:
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        fh.write("$ " + " ".join(job["cmd"]) + "\n")
        fh.flush()
        proc = subprocess.run(job["cmd"], cwd=code, env=env, stdout=fh, stderr=subprocess.STDOUT)
    return {**job, "exit_code": proc.returncode, "wall_s": round(time.perf_counter() - t0, 2)}


def cmd_record(args) -> int:
    from tqdm import tqdm

    code = args.code.resolve()
    out = args.out_dir.resolve()
    if not (code / "sumo_avoid" / "cli.py").is_file():
        print(f"record: {code} has no sumo_avoid/cli.py", file=sys.stderr)
        return 2
    if out.exists() and any(out.iterdir()):
        print(f"record: {out} exists and is not empty; record into a new folder", file=sys.stderr)
        return 2
    try:
        out.relative_to(code)
        print(f"record: warning: {out} is inside the code checkout {code}", file=sys.stderr)
    except ValueError:
        pass
    env = child_env(code)
    probe = subprocess.run([sys.executable, "-c", PROBE], cwd=code, env=env, capture_output=True, text=True)
    build = json.loads(probe.stdout) if probe.returncode == 0 else {}
    imported = pathlib.Path(build.pop("sumo_avoid")).resolve() if build else None
    if imported is None or imported.parent.parent != code:
        print(f"record: with PYTHONPATH={code}, sumo_avoid is imported from {imported} "
              f"(expected {code / 'sumo_avoid'}); {probe.stderr.strip()}", file=sys.stderr)
        return 2

    scenarios, skipped = single_run_scenarios(code)
    if args.no_singles:
        scenarios = []
    entries = [x for suite in args.suite or [] for x in suite_entries(code, suite)]
    names = {p.stem for p in scenarios} | ({TABLE4} if not args.no_singles else set()) | {n for n, _ in entries}
    only = set(args.only or [])
    unknown = only - names
    if unknown:
        print(f"record: --only {sorted(unknown)}: not among {sorted(names)}", file=sys.stderr)
        return 2
    jobs = []
    if not args.no_singles and (not only or TABLE4 in only):  # the longest job first, so it overlaps the scenario runs
        jobs.append({"name": TABLE4, "scenario": None, "seed": None, "out": TABLE4,
                     "cmd": [sys.executable, "-m", "sumo_avoid.cli", "reproduce", "table4", "--seeds", "3",
                             "--out", str(out / TABLE4), "--jobs", "1"]})
    for p in scenarios:
        if only and p.stem not in only:
            continue
        for s in args.seeds:
            rel = f"runs/{p.stem}-s{s}"
            jobs.append({"name": f"{p.stem}-s{s}", "scenario": p.stem, "seed": s, "out": rel,
                         "cmd": [sys.executable, "-m", "sumo_avoid.cli", "run", str(p.relative_to(code)),
                                 "--seed", str(s), "--out", str(out / rel), "--no-plots", "--quiet"]})
    for name, run_args in entries:
        if only and name not in only:
            continue
        for s in args.seeds:
            rel = f"runs/{name}-s{s}"
            jobs.append({"name": f"{name}-s{s}", "scenario": name, "seed": s, "out": rel,
                         "cmd": [sys.executable, "-m", "sumo_avoid.cli", "run", *run_args,
                                 "--seed", str(s), "--out", str(out / rel), "--no-plots", "--quiet"]})
    (out / "logs").mkdir(parents=True, exist_ok=True)
    manifest = {
        "code": str(code),
        "code_commit": _git(code, "rev-parse", "HEAD"),
        "code_tracked_changes": _git(code, "status", "--porcelain", "--untracked-files=no"),
        "imported_sumo_avoid": str(imported),
        "python": sys.executable,
        "python_version": platform.python_version(),
        "machine": platform.machine(),
        "build": build,  # numpy / numba versions and the SIMD kernels numpy dispatches here
        "env": {**CHILD_ENV, "PYTHONPATH": str(code)},
        "seeds": args.seeds,
        "only": sorted(only),
        "scenarios": [p.name for p in scenarios],
        "suites": list(args.suite or []),
        "skipped": [{"file": f, "why": why} for f, why in skipped],
        "workers": args.workers,
        "started": time.strftime("%Y-%m-%d %H:%M:%S"),
        "jobs": [],
    }
    for f, why in skipped:
        print(f"skipping scenarios/{f}: {why}")
    print(f"recording {len(jobs)} jobs of {code} (commit {manifest['code_commit']}) into {out}, "
          f"{args.workers} workers")
    t0 = time.perf_counter()
    results = []
    with cf.ProcessPoolExecutor(args.workers) as pool:
        futs = {pool.submit(_run_job, j, str(code), env, str(out / "logs" / f"{j['name']}.log")): j for j in jobs}
        with tqdm(total=len(futs), unit="run", dynamic_ncols=True) as bar:
            for fut in cf.as_completed(futs):
                r = fut.result()
                results.append(r)
                bar.set_postfix_str(f"{r['name']} {r['wall_s']:.0f} s")
                if r["exit_code"] != 0:
                    tqdm.write(f"FAILED {r['name']}: exit code {r['exit_code']} (log: logs/{r['name']}.log)")
                bar.update()
    order = {j["name"]: i for i, j in enumerate(jobs)}
    manifest["jobs"] = sorted(results, key=lambda r: order[r["name"]])
    manifest["wall_s"] = round(time.perf_counter() - t0, 1)
    (out / "record.json").write_text(json.dumps(manifest, indent=1) + "\n")
    failed = [r for r in results if r["exit_code"] != 0]
    print(f"recorded {len(jobs) - len(failed)} of {len(jobs)} jobs in {manifest['wall_s']:.0f} s -> {out}")
    if failed:
        print(f"error: {len(failed)} job(s) failed: " + ", ".join(f"{r['name']} (exit {r['exit_code']})"
                                                               for r in failed), file=sys.stderr)
        return 1
    return 0


# ---------------------------------------------------------------------------------------- compare
def rel_diff(a: float, b: float) -> float:
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    if math.isnan(a) or math.isnan(b) or math.isinf(a) or math.isinf(b):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b))


def _number(x):
    if isinstance(x, bool):
        return None
    if isinstance(x, (int, float)):
        return float(x)
    return None


def _strip_wall(x):
    if isinstance(x, dict):
        return {k: _strip_wall(v) for k, v in x.items() if k not in WALL_CLOCK_KEYS}
    if isinstance(x, list):
        return [_strip_wall(v) for v in x]
    return x


def _json_diff(a, b, path: str, out: dict) -> None:
    """out: key path (list indices as []) -> largest relative difference there."""
    def note(p, d):
        p = re.sub(r"\[\d+\]", "[]", p) or "(top)"
        out[p] = max(out.get(p, 0.0), d)

    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            p = f"{path}.{k}" if path else str(k)
            if k not in a or k not in b:
                note(p, math.inf)
            else:
                _json_diff(a[k], b[k], p, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            note(f"{path}(length {len(a)} vs {len(b)})", math.inf)
        for i, (x, y) in enumerate(zip(a, b)):
            _json_diff(x, y, f"{path}[{i}]", out)
    else:
        na, nb = _number(a), _number(b)
        if na is not None and nb is not None:
            d = rel_diff(na, nb)
            if d > 0 or type(a) is not type(b):
                note(path, d if d > 0 else math.inf)  # 1 vs 1.0: the file changed, call it structural
        elif a != b or type(a) is not type(b):
            note(path, math.inf)


def _cell(s: str):
    try:
        return float(s)
    except ValueError:
        return None


def _csv_diff(pa: pathlib.Path, pb: pathlib.Path) -> dict:
    """column -> largest relative difference in it; row-count / header changes as pseudo-columns."""
    with open(pa, newline="") as fa, open(pb, newline="") as fb:
        ra, rb = list(csv.reader(fa)), list(csv.reader(fb))
    out: dict[str, float] = {}
    ha, hb = (ra[0] if ra else []), (rb[0] if rb else [])
    if ha != hb:
        out[f"(header: only base {[c for c in ha if c not in hb]}, only new {[c for c in hb if c not in ha]}, "
            f"order {'same' if [c for c in ha if c in hb] == [c for c in hb if c in ha] else 'changed'})"] = math.inf
    if len(ra) != len(rb):
        out[f"(rows {len(ra) - 1} vs {len(rb) - 1})"] = math.inf
    ib = {c: i for i, c in enumerate(hb)}
    cols = [(c, i, ib[c]) for i, c in enumerate(ha) if c in ib]
    for row_a, row_b in zip(ra[1:], rb[1:]):
        if row_a == row_b:
            continue
        for c, i, j in cols:
            x = row_a[i] if i < len(row_a) else None
            y = row_b[j] if j < len(row_b) else None
            if x == y:
                continue
            fx, fy = (_cell(x) if x is not None else None), (_cell(y) if y is not None else None)
            d = rel_diff(fx, fy) if fx is not None and fy is not None else math.inf
            if d == 0.0:  # same number written differently ("1" vs "1.0"): bytes changed anyway
                d = math.inf
            out[c] = max(out.get(c, 0.0), d)
    return out


def compare_file(pa: pathlib.Path, pb: pathlib.Path, *, strip_wall: bool) -> tuple[str, dict]:
    """-> (status, details): status 'identical' | 'differs' | 'missing'; details key -> rel diff."""
    if not pa.is_file() or not pb.is_file():
        where = "base" if not pa.is_file() else "new"
        return "missing", {f"(missing in {where})": math.inf}
    ba, bb = pa.read_bytes(), pb.read_bytes()
    if ba == bb:
        return "identical", {}
    details: dict[str, float] = {}
    if pa.suffix == ".json":
        try:
            ja, jb = json.loads(ba), json.loads(bb)
        except ValueError as e:
            return "differs", {f"(not JSON: {e})": math.inf}
        if strip_wall:
            ja, jb = _strip_wall(ja), _strip_wall(jb)
            if json.dumps(ja, sort_keys=True) == json.dumps(jb, sort_keys=True) and type(ja) is type(jb):
                return "identical", {}  # only wall-clock fields differ
        _json_diff(ja, jb, "", details)
        if not details:
            details["(formatting / key order)"] = math.inf
    elif pa.suffix == ".csv":
        details = _csv_diff(pa, pb)
        if not details:
            details["(formatting / line endings)"] = math.inf
    else:
        details["(bytes)"] = math.inf
    return "differs", details


def _manifest(d: pathlib.Path) -> dict:
    p = d / "record.json"
    if not p.is_file():
        raise SystemExit(f"compare: {d} has no record.json (not a record made by this script)")
    return json.loads(p.read_text())


def _fmt(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:.3g}"


def cmd_compare(args) -> int:
    base, new = args.base_dir.resolve(), args.new_dir.resolve()
    mb, mn = _manifest(base), _manifest(new)
    jb, jn = {j["name"]: j for j in mb["jobs"]}, {j["name"]: j for j in mn["jobs"]}
    only = set(args.only or [])

    def wanted(name: str) -> bool:
        return not only or name in only or name.rsplit("-s", 1)[0] in only

    names = sorted(n for n in set(jb) | set(jn) if wanted(n))
    if only and not names:
        raise SystemExit(f"compare: --only {sorted(only)} matches no job of either record")
    print(f"base {base} (code {mb.get('code_commit')}), new {new} (code {mn.get('code_commit')})"
          + (f", only {sorted(only)}" if only else ""))
    if mb.get("build") != mn.get("build"):  # two machines or builds: bytes may differ in the last bits
        print(f"builds differ: base {mb.get('build')}, new {mn.get('build')}")
    problems = 0
    for n in names:
        for side, jobs in (("base", jb), ("new", jn)):
            if n not in jobs:
                print(f"JOB {n}: not in the {side} record")
                problems += 1
            elif jobs[n]["exit_code"] != 0:
                print(f"JOB {n}: failed in the {side} record (exit code {jobs[n]['exit_code']})")
                problems += 1

    pairs: list[tuple[str, bool]] = []  # (relative path, is a table4 file)
    for n in names:
        if n == TABLE4:
            files = set()
            for root in (base, new):
                d = root / TABLE4
                if d.is_dir():
                    files |= {str(p.relative_to(root)) for p in d.rglob("*")
                              if p.suffix in (".csv", ".json") and p.name not in NEVER_COMPARED}
            if not files:
                files = {f"{TABLE4}/table4.csv"}
            pairs += [(f, True) for f in sorted(files)]
        else:
            rel = (jb.get(n) or jn.get(n))["out"]
            for f in RUN_FILES:
                if f == "detections.csv" and not ((base / rel / f).exists() or (new / rel / f).exists()):
                    continue
                pairs.append((f"{rel}/{f}", False))

    identical, allowed, largest = 0, 0, 0.0
    for rel, is_table4 in pairs:
        status, details = compare_file(base / rel, new / rel, strip_wall=is_table4)
        if status == "identical":
            identical += 1
            continue
        worst = max(details.values())
        largest = max(largest, worst)
        tol = max(args.tolerance, TABLE4_REL_TOL) if is_table4 else args.tolerance
        ok = worst <= tol if args.tolerance > 0 else is_table4 and worst < TABLE4_REL_TOL
        allowed += ok
        what = ", ".join(f"{k} ({_fmt(v)})" for k, v in sorted(details.items(), key=lambda kv: -kv[1])[:12])
        more = f" and {len(details) - 12} more" if len(details) > 12 else ""
        verdict = f"within {tol:g} (allowed)" if ok else status.upper()
        print(f"{verdict} {rel}: largest relative difference {_fmt(worst)}; differs in {what}{more}")
    within = (f" ({allowed} file(s) within the tolerance {args.tolerance:g})" if args.tolerance > 0
              else f" ({allowed} table4 file(s) within {TABLE4_REL_TOL:g})")
    print(f"identical: {identical} of {len(pairs)} files; largest relative difference: {_fmt(largest)}"
          + (within if allowed else "")
          + (f"; {problems} job problem(s)" if problems else ""))
    return 0 if identical + allowed == len(pairs) and problems == 0 else 1


def _tolerance(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        x = math.nan
    if not (0.0 <= x < 1.0):
        raise argparse.ArgumentTypeError(f"bad tolerance {text!r} (a relative difference in [0, 1), e.g. 1e-9)")
    return x


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("record", help="run every scenario and seed plus table4, keep the outputs")
    r.add_argument("out_dir", type=pathlib.Path)
    r.add_argument("--code", type=pathlib.Path, default=ROOT, help="code checkout to run (default: this one)")
    r.add_argument("--seeds", type=parse_seeds, default=parse_seeds("1-3"), help="e.g. 1-3 or 1,2,5 (default 1-3)")
    r.add_argument("--workers", type=int, default=2, help="jobs at a time (default 2)")
    r.add_argument("--suite", action="append", metavar="FILE",
                   help="also every entry of this scenario suite (repeatable), e.g. scenarios/streets.toml")
    r.add_argument("--no-singles", action="store_true", help="leave out the single-run scenarios and table4")
    r.add_argument("--only", action="append", metavar="NAME",
                   help="only this scenario (file stem) or 'table4'; repeatable")
    c = sub.add_parser("compare", help="compare two records; exit 0 when the behaviour is the same")
    c.add_argument("base_dir", type=pathlib.Path)
    c.add_argument("new_dir", type=pathlib.Path)
    c.add_argument("--only", action="append", metavar="NAME",
                   help="compare only this scenario / job name or 'table4'; repeatable")
    c.add_argument("--tolerance", type=_tolerance, default=0.0, metavar="REL",
                   help="records of two machines / builds: numbers may differ by up to REL relative "
                        "(default 0: byte-identical)")
    args = ap.parse_args(argv)
    return cmd_record(args) if args.command == "record" else cmd_compare(args)


if __name__ == "__main__":
    sys.exit(main())
