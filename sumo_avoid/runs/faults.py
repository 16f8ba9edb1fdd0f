"""Test-only fault injection: make chosen runs' processes crash for real, from outside the run's identity.

The environment variable ``SUMO_AVOID_INJECT_CRASH`` names the crashes, ``KIND:TARGET`` separated by
commas, e.g. ``abort:102`` or ``segfault_mid_run:*,segfault:3f2a9c01``:

* ``KIND``: ``segfault`` (a NULL dereference, a real SIGSEGV in native code) or ``abort``
  (``os.abort()``), both after the scenario is loaded and before SUMO starts; ``segfault_mid_run``:
  a SIGSEGV once the simulation has run :data:`CRASH_AT_S` (SUMO running);
* ``TARGET``: a seed (digits: the runs with that seed), a prefix of the run key, or ``*`` (every run).

The parent reads the variable each time it dispatches a run (:func:`crash_for`, in
:func:`sumo_avoid.runs.worker.run_in`) and sends the crash beside the job, never in it: the job and
its run key are the same with or without injection. (A real input that segfaults SUMO 1.28:
``tests/data/segfault_net.toml``, see docs/batch.md.)
"""
from __future__ import annotations

import os

from sumo_avoid.core.config import ScenarioError
from sumo_avoid.runs.job import RunJob

ENV = "SUMO_AVOID_INJECT_CRASH"
CRASHES = ("segfault", "abort", "segfault_mid_run")
CRASH_AT_S = 1.0  # "segfault_mid_run": SIGSEGV once the simulation has run this long


def rules(text: str | None = None) -> tuple[tuple[str, str], ...]:
    """The (kind, target) pairs of ``text`` (default: the environment variable); raises ScenarioError."""
    text = os.environ.get(ENV, "") if text is None else text
    out = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        kind, sep, target = part.partition(":")
        if kind not in CRASHES or not sep or not target:
            raise ScenarioError("<environment>", ENV, f"KIND:TARGET[,KIND:TARGET...], KIND one of {list(CRASHES)}, "
                                "TARGET a seed, a run-key prefix or *", text)
        out.append((kind, target))
    return tuple(out)


def crash_for(job: RunJob, text: str | None = None) -> str | None:
    """The crash injected into ``job`` (the first rule that targets it), or None."""
    for kind, target in rules(text):
        if target == "*" or (target.isdigit() and job.seed == int(target)) or (
                not target.isdigit() and job.key.startswith(target)):
            return kind
    return None


def crash(kind: str) -> None:
    """Crash this process now: ``segfault`` or ``abort``."""
    if kind == "segfault":
        import ctypes

        ctypes.string_at(0)  # NULL dereference: SIGSEGV
    elif kind == "abort":
        os.abort()


class CrashAt:
    """Rollout callback: a real SIGSEGV once simulated time reaches ``time_s``, with SUMO running."""

    def __init__(self, time_s: float):
        self.time_s = time_s

    def on_step(self, snap, n_steps: int) -> None:
        if snap.time_s >= self.time_s:
            crash("segfault")

    def on_end(self) -> None:
        pass
