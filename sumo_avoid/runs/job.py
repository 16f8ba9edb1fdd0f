"""What a run's child process is asked to do (:class:`RunJob`) and what came of it (:class:`RunOutcome`).

Both cross a process boundary as JSON (the fork server's pipe, a spawned worker's argument, the
run's ``result.json``), serialised here and nowhere else (``to_json`` / ``from_json``). The job is
the run's identity and inputs only: how it is started (fork server, fresh interpreter, a fork of
the caller) and test-only fault injection (:mod:`sumo_avoid.runs.faults`) travel beside it, in the
dispatch message of :mod:`sumo_avoid.runs.worker`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Mapping

SCENARIO = "scenario"  # the standard job kind: metrics.json, trajectories.csv, the plug-ins' tables and plots
STATUSES = ("done", "failed", "crashed", "timeout")
# a child that cannot write even its result exits with UNWRITABLE_RC + errno (errno < 156), the parent
# reads the reason from that code: its folder is on a full disk, read-only or gone
UNWRITABLE_RC = 100


@dataclass(frozen=True)
class RunJob:
    """One run for a child process: which scenario, with what, and what the child does after the rollout.

    ``kind``: :data:`SCENARIO` (write the run's files: :func:`sumo_avoid.runs.outputs.write_outputs`) or
    ``"package.module:function"``, a function ``(RunResult, RunJob, out_dir: pathlib.Path) -> dict`` the
    child imports and calls instead; its dict (JSON values) is the outcome's ``metrics``. ``params``
    holds that function's own inputs (JSON values).
    """

    scenario: str  # absolute path of the scenario file
    seed: int | None = None  # None: the scenario's own sim.seed
    overrides: tuple[str, ...] = ()  # KEY=VALUE
    controller: str | None = None  # None: the scenario's own ego.controller
    plots: bool = True  # the SCENARIO kind writes the PNG plots (if the scenario's output.plots allows)
    key: str = "run"  # the run key (batch.plan); names the run's folder
    kind: str = SCENARIO
    params: Mapping[str, Any] = field(default_factory=dict)
    out_dir: str = ""  # the folder the child writes into (filled in when the job is dispatched)
    progress: bool = False  # the child writes its simulated time to out_dir/progress (runs.watch.ProgressFile)

    def __post_init__(self):
        module, sep, name = self.kind.partition(":")
        if self.kind != SCENARIO and not (sep and module and name.isidentifier()):
            raise ValueError(f"RunJob.kind must be {SCENARIO!r} or 'package.module:function', not {self.kind!r}")

    def to_json(self) -> dict:
        return {"scenario": self.scenario, "seed": self.seed, "overrides": list(self.overrides),
                "controller": self.controller, "plots": self.plots, "key": self.key, "kind": self.kind,
                "params": dict(self.params), "out_dir": self.out_dir, "progress": self.progress}

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> RunJob:
        return cls(**{**d, "overrides": tuple(d.get("overrides", ())), "params": dict(d.get("params", {}))})


@dataclass(frozen=True)
class RunOutcome:
    """What came of one :class:`RunJob`; the child writes its part, the parent adds its own.

    ``status``: ``done``; ``failed`` (the run raised: its one-line ``error``, and ``bad_input`` when the
    input was found bad only once SUMO ran, ``unwritable`` when a file could not be written); ``crashed`` (the process ended without a result: died by a
    signal, ``where`` = the Python frame it died in, or exited without one); ``timeout`` (killed at
    its timeout). ``clock_s``: event -> wall-clock time (s since the epoch), every event named ``*_wall``.
    """

    status: str
    error: str | None = None  # one line
    where: str | None = None  # crashed: the innermost Python frame faulthandler wrote, e.g. libsumo/libsumo.py:3545 (start)
    bad_input: str | None = None
    unwritable: list | None = None  # [path, reason]: an output that could not be written (the run's files are void)
    metrics: dict | None = None  # the kind's result: metrics.json's content for SCENARIO
    timings_s: dict = field(default_factory=dict)  # the rollout's wall-clock phases (setup_s, loop_s, total_s)
    cpu_s: float | None = None  # the child's CPU time
    clock_s: dict = field(default_factory=dict)
    overhead_s: float | None = None  # from dispatch to SUMO's start (process start, imports, scenario load)
    started_at: str | None = None  # ISO 8601, UTC
    ended_at: str | None = None
    wall_s: float | None = None  # from dispatch to the parent's reading of the result
    start: str | None = None  # how the child was started: fork, spawn or here
    artifacts: str | None = None  # the folder holding the run's files

    def __post_init__(self):
        if self.status not in STATUSES:
            raise ValueError(f"RunOutcome.status must be one of {STATUSES}, not {self.status!r}")

    @property
    def ok(self) -> bool:
        return self.status == "done"

    @property
    def ledger_status(self) -> str:
        """The ledger's two statuses: ``done``, or ``failed`` for every way a run can fail."""
        return "done" if self.ok else "failed"

    def to_json(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> RunOutcome:
        return cls(**d)
