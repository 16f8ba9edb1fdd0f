"""The batch and suite file formats, as frozen dataclasses validated by :func:`core.config.build`,
the same mechanism as scenario files (one error form: file, dotted key, what was expected).

Seeds are kept as written (``"1-20"``, ``7`` or ``[1, 3]``) and expanded by
:func:`sumo_avoid.studies.batch.parse_seeds`; paths are relative to the file that names them.
"""
from __future__ import annotations

from dataclasses import dataclass

from sumo_avoid.core.config import FieldError, field_doc

Seeds = str | int | tuple[int, ...]


@dataclass(frozen=True)
class BatchRuns:
    """One ``[[runs]]`` table: a scenario x seeds x controllers x grid points."""

    scenario: str = field_doc(nonempty=True, doc="scenario file, relative to the batch file")
    seeds: Seeds = field_doc(doc='seeds: "1-20", "1,3,7" or a list of integers')
    set: tuple[str, ...] = field_doc((), doc="KEY=VALUE overrides for every run of this table")
    controllers: tuple[str, ...] = field_doc((), doc="one run per controller (default: the scenario's)")
    grid: dict = field_doc(default_factory=dict, doc="dotted key -> list of values; one run per combination")
    inject_crash: str | None = field_doc(None, doc="test-only fault injection (docs/batch.md)")

    def __post_init__(self):
        for k, v in self.grid.items():
            if not isinstance(v, list) or not v:
                raise FieldError(f"grid.{k}", "a non-empty list of values", v)


@dataclass(frozen=True)
class BatchFile:
    """A batch TOML file."""

    runs: tuple[BatchRuns, ...] = field_doc(nonempty=True, doc="[[runs]] tables")
    workers: int | None = field_doc(None, positive=True, doc="parallel runs (default: number of cores)")
    timeout_s: float | None = field_doc(None, positive=True, doc="per-run timeout, s (default 600)")
    ledger: str | None = field_doc(None, nonempty=True, doc="SQLite ledger, relative to the batch file")


@dataclass(frozen=True)
class SuiteDefaults:
    """``[defaults]`` of a suite file: seeds and overrides for every entry."""

    seeds: Seeds | None = field_doc(None, doc="seeds of every entry that names none")
    set: tuple[str, ...] = field_doc((), doc="KEY=VALUE overrides put before each entry's own")


@dataclass(frozen=True)
class SuiteEntry:
    """One ``[[entry]]`` of a suite: a scenario, a controller, seeds and pass criteria."""

    name: str = field_doc(nonempty=True, doc="entry name, unique in the suite")
    scenario: str = field_doc(nonempty=True, doc="scenario file, relative to the suite file")
    criteria: tuple[str, ...] = field_doc(nonempty=True, doc="criteria like 'collisions == 0'")
    controller: str | None = field_doc(None, doc="controller (default: the scenario's)")
    seeds: Seeds | None = field_doc(None, doc="seeds (default: [defaults].seeds)")
    set: tuple[str, ...] = field_doc((), doc="KEY=VALUE overrides")


@dataclass(frozen=True)
class SuiteFile:
    """A suite TOML file."""

    entry: tuple[SuiteEntry, ...] = field_doc(nonempty=True, doc="[[entry]] tables")
    defaults: SuiteDefaults = field_doc(default_factory=SuiteDefaults, doc="[defaults]")

    def __post_init__(self):
        seen = set()
        for i, e in enumerate(self.entry):
            if e.name in seen:
                raise FieldError(f"entry[{i}].name", "a name not used by another entry", e.name)
            seen.add(e.name)
