"""Validation of nested plain data (from TOML) into frozen dataclasses: the one mechanism for
scenario, batch and suite files.

A file format is a tree of frozen dataclasses whose fields carry their doc and constraints
(:func:`field_doc`: ``signed``, ``positive``, ``nonempty``); lists of tables are
``tuple[SomeDataclass, ...]``. :func:`build` walks the data against the tree. Every error names the
file, the dotted key and what was expected, and is raised as :class:`ScenarioError`; the CLI
prints it as one line and exits with code 2. Cross-field checks live in ``__post_init__`` and raise
:class:`FieldError` (naming the key) or ``ValueError`` (the table as a whole).
"""
from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any


class ScenarioError(ValueError):
    """A scenario (or an override) is malformed. ``str(err)`` is the one-line message."""

    def __init__(self, file: str, key: str, expected: str, got: Any = None, *, show_got: bool = True):
        self.file, self.key, self.expected, self.got, self.show_got = file, key, expected, got, show_got
        got_txt = f", got {got!r}" if show_got else ""
        super().__init__(f"{file}: key '{key}': expected {expected}{got_txt}")

    def __reduce__(self):  # picklable: raised in a pool worker, it must reach the parent whole
        return _rebuild_error, (self.file, self.key, self.expected, self.got, self.show_got)


def _rebuild_error(file, key, expected, got, show_got) -> ScenarioError:
    return ScenarioError(file, key, expected, got, show_got=show_got)


class ScenarioErrors(ValueError):
    """Several bad inputs found at once (a batch names them all before it runs): one line each."""

    def __init__(self, errors):
        self.errors = list(errors)
        super().__init__("\n".join(str(e) for e in self.errors))

    def __reduce__(self):
        return ScenarioErrors, (self.errors,)


class FieldError(ValueError):
    """Raised by a config dataclass's ``__post_init__``: field ``key`` (relative to the table)
    is wrong; ``expected`` says what it should be. :func:`build` adds the file and the prefix."""

    def __init__(self, key: str, expected: str, got: Any = None, *, show_got: bool = True):
        self.key, self.expected, self.got, self.show_got = key, expected, got, show_got
        super().__init__(f"{key}: expected {expected}")


def field_doc(default=dataclasses.MISSING, *, doc: str = "", signed: bool = False, positive: bool = False,
              nonempty: bool = False, inline: bool = False, **kw):
    """A dataclass field with a docstring (units!) and its constraints: negative numbers allowed
    (``signed``), strictly positive (``positive``), a non-empty string or list (``nonempty``).
    ``inline``: a dataclass field whose keys are read from the enclosing table itself, not from a
    sub-table (a parameter set composed of another's keys and its own: ``[controllers.apf_sa]``)."""
    return dataclasses.field(default=default, metadata={"doc": doc, "signed": signed, "positive": positive,
                                                        "nonempty": nonempty, "inline": inline}, **kw)


def _inline(f: dataclasses.Field) -> bool:
    return bool(f.metadata.get("inline"))


def table_keys(cls) -> list[str]:
    """The keys of the table of config dataclass ``cls`` (an inline field's keys in its place)."""
    hints = typing.get_type_hints(cls)
    return [k for f in dataclasses.fields(cls) for k in (table_keys(hints[f.name]) if _inline(f) else [f.name])]


_NO_CONSTRAINTS = {"signed": False, "positive": False, "nonempty": False}


def _type_name(tp) -> str:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_name(a) for a in typing.get_args(tp))
    if origin in (tuple, list):
        return f"a list of {_type_name(typing.get_args(tp)[0])}"
    if origin is dict:
        return f"a table of ({_type_name(typing.get_args(tp)[1])})"
    return {float: "a number", int: "an integer", str: "a string", bool: "true/false",
            type(None): "nothing"}.get(tp, getattr(tp, "__name__", str(tp)))


def _signed(value, meta, file: str, key: str, noun: str):
    """``value`` if its sign is allowed by the field's ``positive`` / ``signed`` constraints."""
    if meta["positive"] and value <= 0:
        raise ScenarioError(file, key, f"a positive {noun}", value)
    if value < 0 and not meta["signed"]:
        raise ScenarioError(file, key, f"a non-negative {noun}", value)
    return value


def _coerce(value, tp, file: str, key: str, meta):
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _coerce(value, a, file, key, meta)
            except ScenarioError as e:
                errors.append(e)
        if len(errors) == 1:  # Optional[X]: X's own message ("a positive number", not "a number or nothing")
            raise errors[0]
        raise ScenarioError(file, key, _type_name(tp), value)
    if origin in (tuple, list):
        if not isinstance(value, (list, tuple)):
            raise ScenarioError(file, key, _type_name(tp), value)
        if meta["nonempty"] and not value:
            raise ScenarioError(file, key, f"a non-empty list of {_type_name(typing.get_args(tp)[0])}", value)
        item_tp = typing.get_args(tp)[0]
        item_meta = {**meta, "nonempty": False}
        return tuple(_coerce(v, item_tp, file, f"{key}[{i}]", item_meta) for i, v in enumerate(value))
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ScenarioError(file, key, "a number", value)
        value = float(value)
        if not math.isfinite(value):
            raise ScenarioError(file, key, "a finite number", value)
        return _signed(value, meta, file, key, "number")
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(file, key, "an integer", value)
        return _signed(value, meta, file, key, "integer")
    if tp is bool:
        if not isinstance(value, bool):
            raise ScenarioError(file, key, "true or false", value)
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ScenarioError(file, key, "a string", value)
        if meta["nonempty"] and not value:
            raise ScenarioError(file, key, "a non-empty string", value)
        return value
    if dataclasses.is_dataclass(tp):
        return build(tp, value, file, key)
    if tp is dict or typing.get_origin(tp) is dict:
        if not isinstance(value, dict):
            raise ScenarioError(file, key, _type_name(tp) if typing.get_args(tp) else "a table", value)
        if not typing.get_args(tp):
            return value
        item_tp = typing.get_args(tp)[1]  # dict[str, X]: every value is checked as X
        return {k: _coerce(v, item_tp, file, f"{key}.{k}", meta) for k, v in value.items()}
    raise TypeError(f"unsupported field type {tp!r}")  # programming error, not user input


def build(cls, data, file: str, prefix: str = ""):
    """Build the frozen dataclass ``cls`` from ``data`` (a dict), validating every key."""
    where = prefix or "<top level>"
    if not isinstance(data, dict):
        raise ScenarioError(file, where, "a table", data)
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    known = table_keys(cls)
    unknown = sorted(set(data) - set(known))
    if unknown:
        key = f"{prefix}.{unknown[0]}" if prefix else unknown[0]
        raise ScenarioError(file, key, f"one of the known keys {sorted(known)}", unknown[0], show_got=False)
    kwargs = {}
    for name, f in fields.items():
        key = f"{prefix}.{name}" if prefix else name
        if _inline(f):
            own = set(table_keys(hints[name]))
            kwargs[name] = build(hints[name], {k: v for k, v in data.items() if k in own}, file, prefix)
        elif name in data:
            kwargs[name] = _coerce(data[name], hints[name], file, key, {**_NO_CONSTRAINTS, **f.metadata})
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ScenarioError(file, key, f"a value ({_type_name(hints[name])}); the key is required",
                                show_got=False)
    try:
        return cls(**kwargs)
    except ScenarioError:
        raise
    except FieldError as e:  # a field's check in __post_init__
        key = f"{prefix}.{e.key}" if prefix else e.key
        raise ScenarioError(file, key, e.expected, e.got, show_got=e.show_got) from None
    except ValueError as e:  # cross-field checks in __post_init__
        raise ScenarioError(file, where, str(e), show_got=False) from None


def describe(cls, prefix: str = "") -> list[tuple[str, str, str, str]]:
    """(key, type, default, doc) rows for documentation of a config dataclass."""
    rows = []
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        key = f"{prefix}.{f.name}" if prefix else f.name
        tp = hints[f.name]
        if dataclasses.is_dataclass(tp):
            rows += describe(tp, prefix if _inline(f) else key)
            continue
        if f.default is not dataclasses.MISSING:
            default = repr(f.default)
        elif f.default_factory is not dataclasses.MISSING:
            default = repr(f.default_factory())
        else:
            default = "(required)"
        rows.append((key, _type_name(tp), default, f.metadata.get("doc", "")))
    return rows
