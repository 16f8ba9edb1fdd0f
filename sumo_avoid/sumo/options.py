"""SUMO's options: their names, types and sections as this SUMO release defines them, a SUMO
configuration file (``.sumocfg``) read as SUMO reads it, and option values checked before SUMO starts.

The table is SUMO's own (``sumo --save-template``, run once per process, ~40 ms): every option's
canonical name, synonyms (``n`` / ``net`` for ``net-file``), type (``FILE``, ``TIME``, ``FLOAT``,
``INT``, ``BOOL``, ``STR``, ``STR[]``...) and section (``input``, ``output``, ``processing``,
``report``, ``gui_only``...). A configuration is read like SUMO does: every element with a
``value`` attribute is an option (the section elements only group them; the root's name is free),
synonyms count as their option, and the values of ``FILE`` options -- one file or a comma / space
separated list -- are relative to the configuration's folder unless absolute.
"""
from __future__ import annotations

import functools
import math
import os
import pathlib
import re
import subprocess
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from sumo_avoid.sumo.inputs import open_xml, sumo_binary, sumo_env


class OptionError(ValueError):
    """An option SUMO would refuse: ``option`` (its name as written), what was ``expected``, ``got``."""

    def __init__(self, option: str, expected: str, got=None, show_got: bool = True):
        self.option, self.expected, self.got, self.show_got = option, expected, got, show_got
        super().__init__(f"option '{option}': expected {expected}")


@dataclass(frozen=True)
class Option:
    name: str  # canonical
    type: str
    section: str


@functools.lru_cache(maxsize=1)
def option_table() -> dict[str, Option]:
    """Every option of SUMO by canonical name and by each synonym."""
    with tempfile.TemporaryDirectory(prefix="sumo-avoid-template-") as tmp:
        path = pathlib.Path(tmp) / "template.xml"
        subprocess.run([str(sumo_binary()), "--save-template", str(path)], check=True, capture_output=True,
                       timeout=60, env=sumo_env())
        root = ET.parse(path).getroot()
    table: dict[str, Option] = {}
    for section in root:
        for el in section:
            opt = Option(el.tag, el.attrib.get("type", "STR"), section.tag)
            table[el.tag] = opt
            for syn in el.attrib.get("synonymes", "").split():
                table.setdefault(syn, opt)
    return table


def option(name: str) -> Option:
    """The option ``name`` (canonical or a synonym); raises :class:`OptionError`."""
    opt = option_table().get(name)
    if opt is None:
        raise OptionError(name, "an option of SUMO (`sumo --help` lists them)", name)
    return opt


_BOOLS = {"true", "false", "1", "0", "on", "off", "yes", "no", "x", "-"}


def parse_time(text: str) -> float:
    """SUMO's TIME: seconds, or ``[[D:]H:]M:S``; raises ValueError."""
    parts = text.strip().split(":")
    if len(parts) > 4 or not all(parts):
        raise ValueError(text)
    vals = [float(p) for p in parts]
    seconds = sum(v * f for v, f in zip(reversed(vals), (1, 60, 3600, 86400)))
    if not math.isfinite(seconds):
        raise ValueError(text)
    return seconds


def check_value(name: str, value: str) -> str:
    """``value`` as SUMO reads option ``name`` (its type); raises :class:`OptionError`."""
    t = option(name).type
    try:
        if t == "BOOL" and value.strip().lower() not in _BOOLS:
            raise ValueError(value)
        if t == "INT":
            int(value)
        elif t == "FLOAT" and not math.isfinite(float(value)):
            raise ValueError(value)
        elif t == "TIME":
            parse_time(value)
    except ValueError:
        what = {"BOOL": "true or false", "INT": "an integer", "FLOAT": "a number",
                "TIME": "a time in s (or [D:]H:M:S)"}[t]
        raise OptionError(name, f"{what} (SUMO's type {t})", value) from None
    return value


def split_files(value: str) -> list[str]:
    """A FILE option's value as a list: SUMO separates files by commas or spaces."""
    return [f for f in re.split(r"[,\s]+", value.strip()) if f]


def read_config(path: pathlib.Path) -> dict[str, str]:
    """The options of a SUMO configuration file by canonical name, in file order, ``FILE`` values as
    comma-separated absolute paths (relative ones resolved against the file's folder, as SUMO does);
    raises :class:`OptionError` (``option`` ``<file>`` / ``<syntax>`` for the file itself)."""
    try:
        with open_xml(path) as fh:
            root = ET.parse(fh).getroot()
    except ET.ParseError as e:
        raise OptionError("<syntax>", f"a SUMO configuration in XML ({e})", show_got=False) from None
    except (OSError, EOFError) as e:
        raise OptionError("<file>", f"a readable SUMO configuration ({getattr(e, 'strerror', None) or e})",
                          show_got=False) from None
    base = path.resolve().parent
    out: dict[str, str] = {}
    for el in root.iter():
        if "value" not in el.attrib or el is root:
            continue
        opt = option(el.tag)
        value = check_value(el.tag, el.attrib["value"])
        if opt.type == "FILE":
            value = ",".join(str(base / f) if not os.path.isabs(f) else f for f in split_files(value))
        out[opt.name] = value
    return out
