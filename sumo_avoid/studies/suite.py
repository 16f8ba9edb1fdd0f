"""``sumo-avoid suite SUITE.toml``: gate controllers on a scenario suite (pass/fail table, JUnit XML).

A suite file has ``[[entry]]`` tables: ``name``, ``scenario`` (path relative to the suite file),
``controller``, ``seeds`` (``"1-5"`` or a list), optional ``set`` (KEY=VALUE overrides) and
``criteria``, a list of one-comparison strings in a tiny language that is parsed, never eval'd::

    METRIC OP VALUE          # must hold on every seed, e.g.  collisions == 0,  phi_wall <= 0.1
    METRIC_rate OP VALUE     # share of seeds where the (true/false) metric is true: goal_reached_rate >= 0.9
    METRIC_mean|_median|_min|_max OP VALUE   # aggregate over seeds: min_gap_m_min >= 0.5

OP is one of ``== != <= >= < >``; VALUE a number or ``true``/``false``. METRIC must be a key with
one value per run that a run of the entry writes (:func:`sumo_avoid.runs.declared.metric_keys`,
from the metrics' and plug-ins' declarations), checked before any run starts; a metric without a
value (n/a) and a failed run fail the entry. ``[defaults]`` may give ``seeds`` and ``set`` for
every entry.

``travel_time_ratio`` (:mod:`sumo_avoid.studies.baseline`: time to goal against SUMO's own driver on
the same scenario and seed) may be named like a metric, e.g. ``travel_time_ratio_median <= 1.5``; the
suite then runs the entry's baseline too (controller ``sumo``, same scenario, seeds and overrides)
unless it is a run of the suite already. A seed without a ratio (either did not reach its goal)
fails a per-seed criterion and makes an aggregate n/a.

With ``--junit FILE``, each run of a failed entry gets its viewer page (:mod:`sumo_avoid.watch.viewer`) in
``FILE_viewers/ENTRY-sSEED.html``, and the entry's ``<failure>`` names the runs and those files.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import operator
import pathlib
import re
import statistics
import tempfile
import xml.etree.ElementTree as ET

from sumo_avoid.core.config import ScenarioError, ScenarioErrors, build
from sumo_avoid.core.types import Keys
from sumo_avoid.runs.declared import metric_keys
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.spec import read_toml
from sumo_avoid.studies import baseline, batch, ledger, viewer_links
from sumo_avoid.studies.batch import parse_seeds
from sumo_avoid.studies.files import SuiteFile, check_out_file, make_dirs, remove_dirs, write_atomic

OPS = {"==": operator.eq, "!=": operator.ne, "<=": operator.le, ">=": operator.ge, "<": operator.lt, ">": operator.gt}
AGGREGATES = ("rate", "mean", "median", "min", "max")
_CRIT = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(==|!=|<=|>=|<|>)\s*"
                   r"(true|false|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*$")


@dataclasses.dataclass(frozen=True)
class Criterion:
    text: str
    metric: str
    op: str
    value: float

    @classmethod
    def parse(cls, text: str, file: str = "<criteria>", key: str = "criteria") -> Criterion:
        m = _CRIT.match(text) if isinstance(text, str) else None
        if not m:
            raise ScenarioError(file, key, "a criterion like 'collisions == 0' or 'goal_reached_rate >= 0.9' "
                                "(METRIC OP NUMBER, OP one of == != <= >= < >)", text)
        raw = m.group(3)
        value = {"true": 1.0, "false": 0.0}.get(raw)
        return cls(text.strip(), m.group(1), m.group(2), float(raw) if value is None else value)

    def resolve(self, names) -> tuple[str, str | None] | None:
        """(metric key, aggregate or None) this criterion reads among ``names``; None if it names none."""
        if self.metric in names:
            return self.metric, None
        base, _, suffix = self.metric.rpartition("_")
        return (base, suffix) if suffix in AGGREGATES and base in names else None

    def problem(self, keys: Keys) -> str | None:
        """What is wrong with the metric name given what a run writes (``keys``), or None."""
        if self.resolve(keys.numeric):
            return None
        aggregate = self.metric.rpartition("_")[2] in AGGREGATES
        forms = [f"{k}_{a}" for k in keys.numeric for a in AGGREGATES] if aggregate else keys.numeric
        hint = f"nearest: {', '.join(difflib.get_close_matches(self.metric, forms, n=3, cutoff=0.0))}"
        other = self.resolve(keys.nested) or self.resolve(keys.text)
        if other:
            what = "a list or table, kept only in metrics.json" if other[0] in keys.nested else "text"
            return f"a metric with a number or true/false per run ('{other[0]}' is {what}; {hint})"
        return f"a metric a run of this entry writes, optionally with _{'/_'.join(AGGREGATES)} ({hint})"

    def check(self, rows: list[dict]) -> tuple[bool, str]:
        """Evaluate on the done runs' metric rows. Returns (passed, one-line observation)."""
        if not rows:
            return False, "no finished runs"
        found = self.resolve(rows[0])
        if found is None:
            return False, f"no metric '{self.metric}'"
        name, agg = found
        vals = [_num(r.get(name)) for r in rows]
        seeds = [r.get("seed") for r in rows]
        op = OPS[self.op]
        if agg is None:
            bad = [(s, v) for s, v in zip(seeds, vals) if v is None or not op(v, self.value)]
            if not bad:
                return True, f"ok on {len(rows)}/{len(rows)} seeds"
            shown = ", ".join(f"seed {s}: {'n/a' if v is None else f'{v:g}'}" for s, v in bad[:5])
            return False, f"fails on {len(bad)}/{len(rows)} seeds ({shown}{', ...' if len(bad) > 5 else ''})"
        if any(v is None for v in vals):
            return False, f"{name} is n/a on some seeds"
        if agg == "rate":
            x = sum(1.0 for v in vals if v) / len(vals)
        elif agg == "mean":
            x = sum(vals) / len(vals)
        elif agg == "median":
            x = statistics.median(vals)
        else:
            x = (min if agg == "min" else max)(vals)
        return bool(op(x, self.value)), f"{name} {agg} = {x:.4g} over {len(vals)} seeds"


def _num(v):
    if v is None or isinstance(v, str):
        return None
    v = float(v)
    return None if math.isnan(v) else v


@dataclasses.dataclass(frozen=True)
class Entry:
    name: str
    scenario: pathlib.Path
    controller: str | None
    seeds: tuple[int, ...]
    overrides: tuple[str, ...]
    criteria: tuple[Criterion, ...]


def load(path, seeds_override=None, extra_sets=()) -> list[Entry]:
    """Read and validate a suite file (raises ScenarioError)."""
    path = pathlib.Path(path)
    file = str(path)
    sf = build(SuiteFile, read_toml(path), file)
    out = []
    for i, e in enumerate(sf.entry):
        where = f"entry[{i}]"
        raw_seeds = seeds_override if seeds_override is not None else (e.seeds if e.seeds is not None
                                                                         else sf.defaults.seeds)
        if raw_seeds is None:
            raise ScenarioError(file, f"{where}.seeds", "seeds like \"1-5\" (here or in [defaults])", show_got=False)
        seeds = (parse_seeds(raw_seeds, file, f"{where}.seeds") if seeds_override is None
                 else parse_seeds(seeds_override))
        sets = sf.defaults.set + e.set + tuple(extra_sets)
        parsed = tuple(Criterion.parse(c, file, f"{where}.criteria[{j}]") for j, c in enumerate(e.criteria))
        scn = path.resolve().parent / e.scenario
        if not scn.is_file():
            raise ScenarioError(file, f"{where}.scenario", "an existing scenario file", e.scenario)
        out.append(Entry(e.name, scn, e.controller, seeds, sets, parsed))
    return out


def check_criteria(entries: list[Entry], file: str) -> None:
    """Every criterion names a metric with one value per run that a run of its entry writes (the
    declared keys of the entry's scenario, controller and overrides), before anything runs; raises
    ScenarioError (ScenarioErrors: one line per bad criterion)."""
    errors = []
    for i, e in enumerate(entries):
        scn = scenario.load(e.scenario, list(e.overrides), controller=e.controller, seed=e.seeds[0])
        keys = metric_keys(scn)
        if scn.spec.arena is None:  # the ratio's baseline, SUMO's driver, drives only on a route's lanes
            keys = keys | baseline.KEYS
        for j, c in enumerate(e.criteria):
            problem = c.problem(keys)
            if problem:
                errors.append(ScenarioError(file, f"entry[{i}].criteria[{j}]", problem, c.metric))
    if len(errors) == 1:
        raise errors[0]
    if errors:
        raise ScenarioErrors(errors)


@dataclasses.dataclass(frozen=True)
class EntryResult:
    entry: Entry
    passed: bool
    lines: tuple[tuple[str, bool, str], ...]  # (criterion or "runs", passed, observation)
    time_s: float
    viewers: tuple[tuple[int, str, str], ...] = ()  # a failed entry's runs: (seed, run key, viewer file)


def evaluate(entries: list[Entry], runs_by_entry: dict[str, list], df) -> list[EntryResult]:
    """Check every entry's criteria on its runs' ledger rows (with ``travel_time_ratio``)."""
    df = baseline.with_travel_time_ratio(df)
    out = []
    for e in entries:
        keys = [s.key for s in runs_by_entry[e.name]]
        sub = df[df["key"].isin(keys)]
        rows = sub.to_dict(orient="records")
        done = [r for r in rows if r["status"] == "done"]
        failed = [r for r in rows if r["status"] != "done"]
        lines = []
        if failed or len(rows) != len(keys):
            errs = "; ".join(f"seed {r['seed']}: {r['error']}" for r in failed[:3])
            lines.append(("runs", False, f"{len(failed)} of {len(keys)} runs failed ({errs})"))
        for c in e.criteria:
            ok, obs = c.check(done)
            lines.append((c.text, ok, obs))
        wall = float(sub["wall_s"].fillna(0).sum()) if len(sub) else 0.0
        out.append(EntryResult(e, all(ok for _, ok, _ in lines), tuple(lines), wall))
    return out


def table(results: list[EntryResult]) -> str:
    w = max([len(r.entry.name) for r in results] + [5])
    c = max([len(t) for r in results for t, _, _ in r.lines] + [9])
    lines = [f"{'entry':<{w}}  {'criterion':<{c}}  result  observed", "-" * (w + c + 28)]
    for r in results:
        for i, (text, ok, obs) in enumerate(r.lines):
            lines.append(f"{r.entry.name if i == 0 else '':<{w}}  {text:<{c}}  {'pass' if ok else 'FAIL':<6}  {obs}")
    n_fail = sum(not r.passed for r in results)
    lines.append(f"{len(results) - n_fail} of {len(results)} entries passed" + (f", {n_fail} FAILED" if n_fail else ""))
    return "\n".join(lines)


def junit_xml(results: list[EntryResult], suite_name: str) -> str:
    """JUnit XML: one <testcase> per entry, a <failure> naming what failed."""
    root = ET.Element("testsuites")
    ts = ET.SubElement(root, "testsuite", name=suite_name, tests=str(len(results)),
                       failures=str(sum(not r.passed for r in results)), errors="0",
                       time=f"{sum(r.time_s for r in results):.3f}")
    for r in results:
        tc = ET.SubElement(ts, "testcase", classname=f"sumo_avoid.studies.suite.{suite_name}", name=r.entry.name,
                           time=f"{r.time_s:.3f}")
        bad = [(t, o) for t, ok, o in r.lines if not ok]
        if bad:
            runs = [f"run {k[:16]} (seed {seed}): viewer {path}" for seed, k, path in r.viewers]
            f = ET.SubElement(tc, "failure", message=f"{r.entry.name}: {bad[0][0]}: {bad[0][1]}"
                              + (f"; {runs[0]}" if runs else ""), type="criterion")
            f.text = "\n".join([f"{t}: {o}" for t, o in bad] + runs)
        ET.SubElement(tc, "system-out").text = "\n".join(f"{'pass' if ok else 'FAIL'} {t}: {o}"
                                                        for t, ok, o in r.lines)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def add_parser(sub) -> None:
    s = sub.add_parser("suite", help="run a scenario suite, check its criteria, write JUnit XML")
    s.add_argument("suite", type=pathlib.Path)
    s.add_argument("--junit", type=pathlib.Path, default=None, help="write JUnit XML here")
    s.add_argument("--seeds", default=None, help="use these seeds for every entry (e.g. 1-2 for a quick CI run)")
    s.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="extra override for every entry (e.g. sim.duration_s=30)")
    s.add_argument("--ledger", type=pathlib.Path, default=None,
                   help="keep the runs in this ledger (default: a fresh temporary one, so results reflect the code now)")
    s.add_argument("--workers", type=int, default=None, help="parallel runs (default: number of cores)")
    s.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on a Dask cluster")
    s.add_argument("--timeout", type=float, default=600.0, help="per-run timeout, s")
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    s.set_defaults(func=cmd_suite)


def cmd_suite(args) -> int:
    entries = load(args.suite, args.seeds, args.overrides)
    workers = batch.workers_or_cores(args.workers)
    if not 0 < args.timeout < math.inf:
        raise ScenarioError("<command line>", "--timeout", "a positive number of seconds", args.timeout)
    if args.junit:
        check_out_file(args.junit, "--junit")
    if args.ledger:
        ledger.check(args.ledger, "--ledger")
    runs_by_entry, all_runs, seen = {}, [], set()
    for e in entries:
        runs_by_entry[e.name] = batch.expand([e.scenario], e.seeds, e.overrides, [e.controller])
        for s in runs_by_entry[e.name]:
            if s.key not in seen:
                seen.add(s.key)
                all_runs.append(s)
    check_criteria(entries, str(args.suite))
    n_entry_runs = len(all_runs)
    for e in entries:
        if not any(c.resolve(baseline.KEYS.numeric) for c in e.criteria):
            continue
        for s in batch.expand([e.scenario], e.seeds, e.overrides, [baseline.BASELINE]):  # its ratio's baseline
            if s.key not in seen:
                seen.add(s.key)
                all_runs.append(s)
    made = make_dirs(args.junit.parent, "--junit") if args.junit else []  # a folder that vanishes later: not made again
    try:
        results = _run(args, entries, runs_by_entry, all_runs, workers, len(all_runs) - n_entry_runs)
        print(table(results))
        if args.junit:
            write_atomic(args.junit, junit_xml(results, args.suite.stem))
    except BaseException:
        remove_dirs(made)
        raise
    if args.junit:
        print(f"JUnit XML -> {args.junit}")
    return 0 if all(r.passed for r in results) else 1


def _run(args, entries, runs_by_entry, all_runs, workers, n_baselines: int = 0) -> list[EntryResult]:
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-suite-") as tmp:
        led = args.ledger or pathlib.Path(tmp) / "ledger.sqlite"
        cfg = batch.BatchConfig(tuple(all_runs), led, workers=workers,
                                timeout_s=args.timeout, scheduler=args.scheduler)
        extra = f" ({n_baselines} of them baselines for travel_time_ratio, controller {baseline.BASELINE})" if n_baselines else ""
        print(f"suite {args.suite}: {len(entries)} entries, {len(all_runs)} runs{extra}", flush=True)
        batch.run_batch(cfg, progress=False if args.quiet else None)
        results = evaluate(entries, runs_by_entry, ledger.read(led))
        return with_viewers(results, runs_by_entry, led, args.junit) if args.junit else results


def with_viewers(results: list[EntryResult], runs_by_entry, led: pathlib.Path, junit: pathlib.Path) -> list:
    """Each failed entry's runs get their viewer page beside the JUnit XML (``JUNIT_viewers/ENTRY-sSEED.html``),
    written while the runs' folders exist (a suite's own ledger is temporary), named in its failure."""
    df = ledger.read(led)
    done = df[df["status"] == "done"].sort_values("seed")
    planned, found = {}, {}
    for r in results:
        if r.passed:
            continue
        name = re.sub(r"[^A-Za-z0-9_.-]+", "_", r.entry.name)
        rows = done[done["key"].isin({s.key for s in runs_by_entry[r.entry.name]})]
        for key, (d, net, _) in viewer_links.plan(rows, led.resolve().parent, junit).items():
            seed = int(rows.loc[rows["key"] == key, "seed"].iloc[0])
            path = viewer_links.viewers_dir(junit) / f"{name}-s{seed}.html"
            planned[(r.entry.name, key)] = (d, net, path)
            found.setdefault(r.entry.name, []).append((seed, str(key), str(path)))
    viewer_links.write_planned(planned)
    return [dataclasses.replace(r, viewers=tuple(found.get(r.entry.name, ()))) for r in results]
