"""Batches of runs (scenarios x seeds x parameter grid), each run in its own worker process.

Every run is its own process, forked from a warm fork server or a fresh interpreter
(:mod:`sumo_avoid.runs.worker`; libsumo runs one simulation per process, and a segfault in SUMO must
cost only its own run). A run that raises, dies by a signal or exceeds its timeout is recorded
``failed`` with its cause; the batch goes on. Results go to the SQLite ledger
(:mod:`sumo_avoid.studies.ledger`) one transaction per run, written by this (parent) process only;
re-running the same batch skips the recorded runs. Runs execute on a local pool of ``workers``
threads each waiting on one run's process, or on a Dask cluster (``scheduler``).
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import pathlib
import shutil
import sys
import time
from dataclasses import dataclass, field

from tqdm import tqdm

from sumo_avoid.core.config import ScenarioError, ScenarioErrors, build
from sumo_avoid.core.output_error import OutputError
from sumo_avoid.scenario import spec as scenario
from sumo_avoid.scenario.spec import MAX_SEED, read_toml
from sumo_avoid.scenario.sumocfg import is_sumocfg
from sumo_avoid.runs import faults, worker
from sumo_avoid.runs.job import RunJob, RunOutcome
from sumo_avoid.studies import ledger as ledger_mod
from sumo_avoid.studies import pools
from sumo_avoid.studies.files import BatchFile

KEY_VERSION = b"sumo_avoid-run-key-v1"
MAX_SEEDS = 100_000  # seeds of one --seeds / seeds value: more is a typo (0-1000000000), not a study


@dataclass(frozen=True)
class RunSpec:
    """One run of a batch: its job and what its ledger row says about it."""

    scenario: str  # absolute path of the scenario file
    seed: int
    overrides: tuple[str, ...] = ()
    controller: str | None = None
    key: str = ""
    name: str = ""  # scenario name (filled by plan())
    effective_controller: str = ""
    net_file: str = ""
    plots: bool = True  # the run writes plots (output.plots)
    bad_input: str | None = None  # --keep-going: the input's error; the run is recorded failed, never started

    def job(self) -> RunJob:
        return RunJob(self.scenario, self.seed, self.overrides, self.controller, plots=self.plots, key=self.key)


@dataclass(frozen=True)
class BatchConfig:
    runs: tuple[RunSpec, ...]
    ledger: pathlib.Path
    workers: int = field(default_factory=lambda: os.cpu_count() or 1)
    timeout_s: float = 600.0
    scheduler: str | None = None
    retry_failed: bool = False
    start: str | None = None  # how run processes start: "fork" (warm fork server) or "spawn"; None: best available


def parse_seeds(text, file: str = "<command line>", key: str = "--seeds") -> tuple[int, ...]:
    """``"1-20"``, ``"1,3,7"``, ``"1-3,9"``, an int or a list of ints -> sorted unique seeds."""
    if isinstance(text, bool):
        raise ScenarioError(file, key, "seeds like 1-20 or 1,3,7 or a list of integers", text)
    if isinstance(text, int):
        return parse_seeds([text], file, key)
    if isinstance(text, (list, tuple)):
        if not text or not all(isinstance(s, int) and not isinstance(s, bool) and 0 <= s <= MAX_SEED for s in text):
            raise ScenarioError(file, key, f"a non-empty list of integers in [0, {MAX_SEED}]", text)
        return tuple(sorted(set(text)))
    seeds: set[int] = set()
    for part in str(text).split(","):
        a, _, b = part.strip().partition("-")
        try:
            lo, hi = int(a), int(b) if b else int(a)
        except ValueError:
            lo, hi = -1, -1
        if lo < 0 or hi < lo:
            raise ScenarioError(file, key, "seeds like 1-20 or 1,3,7 (non-negative, A <= B)", text)
        if hi > MAX_SEED or hi - lo + 1 + len(seeds) > MAX_SEEDS:
            raise ScenarioError(file, key, f"at most {MAX_SEEDS} seeds in [0, {MAX_SEED}]", text)
        seeds.update(range(lo, hi + 1))
    return tuple(sorted(seeds))


_hash_cache: dict[tuple[str, int, int], bytes] = {}


def _file_digest(path: pathlib.Path) -> bytes:
    st = path.stat()
    k = (str(path), st.st_mtime_ns, st.st_size)
    if k not in _hash_cache:
        _hash_cache[k] = hashlib.sha256(path.read_bytes()).digest()
    return _hash_cache[k]


def plan(scenario_path, seed: int, overrides=(), controller=None) -> RunSpec:
    """Validate one run (raises ScenarioError) and compute its key: sha256 of the scenario file,
    the net/route/additional files it references, the overrides, controller and seed."""
    path = pathlib.Path(scenario_path).resolve()
    scn = scenario.load(path, list(overrides), controller=controller, seed=seed)
    h = hashlib.sha256(KEY_VERSION)
    for f in (path, scn.net_file, *scn.route_files, *scn.additional_files):
        h.update(_file_digest(f))
    if scn.sumocfg is not None and scn.sumocfg.path != path:  # sim.sumocfg: its options are the run's too
        h.update(_file_digest(scn.sumocfg.path))
    # "inject_crash": None is part of every key, so that keys match those of the ledgers in reports/;
    # test-only crash injection itself lives outside the key (runs/faults.py)
    h.update(json.dumps({"overrides": list(overrides), "controller": scn.spec.ego.controller,
                         "seed": scn.spec.sim.seed, "inject_crash": None}, sort_keys=True).encode())
    return RunSpec(str(path), scn.spec.sim.seed, tuple(overrides), controller, h.hexdigest(),
                   scn.name, scn.spec.ego.controller, str(scn.net_file), scn.spec.output.plots)


def expand(scenarios, seeds, overrides=(), controllers=(None,), grid: dict | None = None) -> list[RunSpec]:
    """scenarios x controllers x grid points x seeds -> validated RunSpecs (duplicates dropped)."""
    grid = grid or {}
    keys = sorted(grid)
    points = [tuple(f"{k}={_toml_value(v)}" for k, v in zip(keys, combo))
              for combo in itertools.product(*(grid[k] for k in keys))] if keys else [()]
    out, seen = [], set()
    for scn, ctl, point, seed in itertools.product(scenarios, controllers or (None,), points, seeds):
        spec = plan(scn, seed, tuple(overrides) + point, ctl)
        if spec.key not in seen:
            seen.add(spec.key)
            out.append(spec)
    return out


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def load_batch_file(path) -> tuple[list[RunSpec], dict]:
    """A batch TOML: top-level ``workers``, ``ledger``, ``timeout_s``; ``[[runs]]`` tables with
    ``scenario``, ``seeds``, optional ``set`` (list of KEY=VALUE), ``controllers`` and ``grid``
    (table: dotted key -> list of values). Paths are relative to the batch file. Returns (runs, options)."""
    path = pathlib.Path(path)
    file = str(path)
    bf = build(BatchFile, read_toml(path), file)
    specs, seen = [], set()
    for i, e in enumerate(bf.runs):
        seeds = parse_seeds(e.seeds, file, f"runs[{i}].seeds")
        scn = (path.resolve().parent / e.scenario)
        if not scn.is_file():
            raise ScenarioError(file, f"runs[{i}].scenario", "an existing scenario file", e.scenario)
        for s in expand([scn], seeds, e.set, e.controllers or (None,), e.grid):
            if s.key not in seen:
                seen.add(s.key)
                specs.append(s)
    opts = {k: v for k, v in (("workers", bf.workers), ("timeout_s", bf.timeout_s)) if v is not None}
    if bf.ledger is not None:
        opts["ledger"] = path.resolve().parent / bf.ledger
    return specs, opts


def artifacts_root(ledger_path) -> pathlib.Path:
    """Per-run artifacts live in ``<ledger folder>/runs/<key[:16]>/``."""
    return pathlib.Path(ledger_path).resolve().parent / "runs"


def _row(spec: RunSpec, res: RunOutcome, root: pathlib.Path) -> dict:
    return {"key": spec.key, "scenario": spec.name, "scenario_path": spec.scenario, "net_file": spec.net_file,
            "controller": spec.effective_controller, "seed": spec.seed, "overrides": json.dumps(list(spec.overrides)),
            "status": res.ledger_status, "error": res.error, "started_at": res.started_at, "ended_at": res.ended_at,
            "wall_s": res.wall_s, "overhead_s": res.overhead_s,
            "artifacts": os.path.relpath(res.artifacts, root.parent) if res.artifacts else None,
            "code": ledger_mod.code_version()}


class _Progress:
    """tqdm bar with done/failed counts and ETA; silent when CI=true or stderr is not a tty."""

    def __init__(self, total: int, enabled: bool | None = None):
        if enabled is None:
            enabled = os.environ.get("CI", "").lower() not in ("1", "true", "yes") and sys.stderr.isatty()
        self.done = self.failed = 0
        self.bar = None
        if enabled and total:
            size = shutil.get_terminal_size((100, 20))  # never 0 (a bare pty reports 0x0: tqdm would hide)
            self.bar = tqdm(total=total, unit="run", ncols=min(size.columns, 120), nrows=size.lines, file=sys.stderr)

    def update(self, ok: bool) -> None:
        self.done += ok
        self.failed += not ok
        if self.bar is not None:
            self.bar.set_postfix(done=self.done, failed=self.failed, refresh=False)
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_batch(cfg: BatchConfig, progress: bool | None = None, log=print) -> dict:
    """Run every run of ``cfg`` not yet in the ledger. Returns counts."""
    root = artifacts_root(cfg.ledger)
    root.mkdir(parents=True, exist_ok=True)
    con = ledger_mod.connect(cfg.ledger)
    try:
        have = ledger_mod.status_of(con)
        skip = {"done", "failed"} if not cfg.retry_failed else {"done"}
        todo = [s for s in cfg.runs if have.get(s.key) not in skip]
        counts = {"total": len(cfg.runs), "skipped": len(cfg.runs) - len(todo), "done": 0, "failed": 0}
        if counts["skipped"]:
            log(f"ledger {cfg.ledger}: {counts['skipped']} of {len(cfg.runs)} runs already recorded, skipped")
            code = ledger_mod.code_version()
            old = ledger_mod.made_by_other_code(con, (s.key for s in cfg.runs), code)
            if old:
                log(f"  warning: {old} of them were made by other plug-in code than this ({code}, "
                    "ledger column `code`); kept, not re-run: use a new ledger to re-run them")
        if todo and not cfg.scheduler and (cfg.start or worker.default_start()) == "fork":
            worker.prestart()  # the fork server imports while the ledger is read and the pool starts
        bar = _Progress(len(todo), progress)
        bad, todo = [s for s in todo if s.bad_input is not None], [s for s in todo if s.bad_input is None]
        unrecorded = {s.key for s in todo if s.key not in have}
        results = (pools.dask_results if cfg.scheduler else pools.local_results)(todo, root, cfg)  # starts when read
        try:
            for spec in bad:  # --keep-going: failed with their cause
                ledger_mod.record(con, _row(spec, RunOutcome("failed", error=f"bad input: {spec.bad_input}"), root))
                counts["failed"] += 1
                bar.update(False)
            for spec, res in results:
                if res.unwritable is not None:  # a full disk, a read-only or vanished folder: the batch stops
                    raise OutputError(*res.unwritable)
                ledger_mod.record(con, _row(spec, res, root), res.metrics)
                unrecorded.discard(spec.key)
                counts[res.ledger_status] += 1
                bar.update(res.ok)
        except OutputError:
            results.close()  # the running runs are killed; the ledger keeps every row recorded so far
            pools.discard_unrecorded(root, unrecorded)
            raise
        finally:
            results.close()
            bar.close()
    finally:
        con.close()
    ledger_mod.export(cfg.ledger, cfg.ledger)
    return counts


# --- command line -------------------------------------------------------------------------------
def add_parser(sub) -> None:
    b = sub.add_parser("batch", help="run scenarios x seeds x parameters in worker processes into a ledger")
    b.add_argument("inputs", nargs="+", type=pathlib.Path, metavar="SCENARIO_OR_BATCH",
                   help="scenario files, or one batch TOML file with [[runs]] tables")
    b.add_argument("--seeds", default=None, help="seeds, e.g. 1-20 or 1,3,7 (scenario files only; default: the scenario's)")
    b.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scenario value for every run (scenario files only)")
    b.add_argument("--controller", dest="controllers", action="append", default=[],
                   help="controller (repeatable: one run per controller; default: the scenario's)")
    b.add_argument("--workers", type=int, default=None, help="parallel runs on this machine (default: number of cores)")
    b.add_argument("--ledger", type=pathlib.Path, default=None,
                   help="SQLite ledger (default: reports/batch/ledger.sqlite); artifacts go next to it in runs/")
    b.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on a Dask cluster, e.g. tcp://host:8786")
    b.add_argument("--timeout", type=float, default=None, help="per-run timeout, s (default 600)")
    b.add_argument("--retry-failed", action="store_true", help="re-run runs recorded as failed")
    b.add_argument("--keep-going", action="store_true", help="bad scenarios do not stop the batch: each is recorded "
                                                             "failed with its cause and the good runs run")
    b.add_argument("--start", default=None, metavar="fork|spawn",
                   help="how each run's process starts: fork (from a warm fork server; default on Linux) "
                        "or spawn (a fresh interpreter per run)")
    b.add_argument("--quiet", action="store_true", help="no progress bar")
    b.set_defaults(func=cmd_batch)


def _is_batch_file(path: pathlib.Path) -> bool:
    return not is_sumocfg(path) and "runs" in read_toml(path)


def config_from_args(args) -> BatchConfig:
    """The batch the command line asks for. Every bad input is found before anything runs: raised
    together (:class:`ScenarioErrors`), or with ``--keep-going`` kept as runs that fail with their cause."""
    _check_flags(args)
    opts: dict = {}
    bad: list[ScenarioError] = []
    if len(args.inputs) == 1 and _is_batch_file(args.inputs[0]):
        if args.seeds or args.overrides or args.controllers:
            raise ScenarioError(str(args.inputs[0]), "--seeds/--set/--controller",
                                "these only with scenario files; a batch file sets them per [[runs]]", show_got=False)
        specs, opts = load_batch_file(args.inputs[0])
    else:
        seeds = parse_seeds(args.seeds) if args.seeds else (None,)
        specs = []
        for p in args.inputs:
            try:
                if _is_batch_file(p):
                    raise ScenarioError(str(p), "runs", "a batch file on its own (one batch file, no scenarios)",
                                        show_got=False)
            except ScenarioError as e:
                bad.append(e)
                specs += [_bad_run(p, seed, args.overrides, ctl, e) for seed in seeds for ctl in args.controllers or [None]]
                continue
            for seed in seeds:
                for ctl in (args.controllers or [None]):
                    try:
                        s = plan(p, seed, tuple(args.overrides), ctl)
                    except ScenarioError as e:
                        bad.append(e)
                        s = _bad_run(p, seed, args.overrides, ctl, e)
                    if s.key not in {x.key for x in specs}:
                        specs.append(s)
    if bad and not args.keep_going:
        unique = list({str(e): e for e in bad}.values())
        raise unique[0] if len(unique) == 1 else ScenarioErrors(unique)
    kw = {"workers": args.workers or opts.get("workers") or os.cpu_count() or 1,
          "timeout_s": args.timeout or opts.get("timeout_s", 600.0)}
    led = args.ledger or opts.get("ledger") or pathlib.Path("reports/batch/ledger.sqlite")
    ledger_mod.check(led, "--ledger")
    return BatchConfig(tuple(specs), pathlib.Path(led), scheduler=args.scheduler, retry_failed=args.retry_failed,
                       start=args.start, **kw)


def workers_or_cores(n: int | None) -> int:
    """A ``--workers`` flag: a positive integer, or None for the number of cores (else ScenarioError)."""
    if n is not None and n < 1:
        raise ScenarioError("<command line>", "--workers", "a positive integer", n)
    return n if n is not None else (os.cpu_count() or 1)


def _check_flags(args) -> None:
    workers_or_cores(args.workers)
    faults.rules()  # test-only fault injection: a malformed SUMO_AVOID_INJECT_CRASH is refused before any run
    if args.timeout is not None and not 0 < args.timeout < math.inf:
        raise ScenarioError("<command line>", "--timeout", "a positive number of seconds", args.timeout)
    if args.start is not None and args.start not in worker.STARTS:
        raise ScenarioError("<command line>", "--start", "fork or spawn", args.start)
    if args.start == "fork" and not args.scheduler and worker.default_start() != "fork":
        raise ScenarioError("<command line>", "--start", "spawn: this system has no fork server (Linux with pidfd)",
                            args.start)


def _bad_run(path, seed, overrides, controller, err: ScenarioError) -> RunSpec:
    """A run whose input is bad (``--keep-going``): recorded failed with the cause, never started. Its key
    covers the path, the arguments and the cause (there may be no file content to hash)."""
    path = pathlib.Path(path).resolve()
    h = hashlib.sha256(KEY_VERSION + b"bad-input")
    h.update(json.dumps({"path": str(path), "seed": seed, "overrides": list(overrides), "controller": controller,
                         "error": str(err)}, sort_keys=True).encode())
    return RunSpec(str(path), seed if seed is not None else -1, tuple(overrides), controller, h.hexdigest(),
                   path.stem, controller or "", "", False, bad_input=str(err))


def cmd_batch(args) -> int:
    if args.scheduler is None and args.start != "spawn":
        worker.prestart()  # its imports (0.6-1.3 s) overlap with planning the runs (a scenario load per run)
    cfg = config_from_args(args)
    where = f"Dask scheduler {cfg.scheduler}" if cfg.scheduler else f"{cfg.workers} local workers"
    print(f"batch: {len(cfg.runs)} runs on {where} -> {cfg.ledger}", flush=True)
    t0 = time.perf_counter()
    try:
        c = run_batch(cfg, progress=False if args.quiet else None)
    except KeyboardInterrupt:
        print("batch: interrupted; running runs killed; re-run the same command to resume", file=sys.stderr)
        return 130
    print(f"batch: {c['done']} done, {c['failed']} failed, {c['skipped']} already recorded "
          f"({time.perf_counter() - t0:.1f} s)")
    df = ledger_mod.read(cfg.ledger)
    keys = {s.key for s in cfg.runs}
    bad = df[df["key"].isin(keys) & (df["status"] == "failed")]
    for r in bad.itertuples():
        print(f"  FAILED {r.scenario} seed {r.seed} [{r.key[:16]}]: {r.error}")
    return 1 if len(bad) else 0
