"""SUMO's own tools for the scenario nets, run so that a rebuild is byte-identical.

Shared by ``scenarios/roads/build.py`` and ``scenarios/generated/make.py``. The tools come from
the eclipse-sumo wheel (``pip install -e .``). SUMO writes a header comment into every file it
makes, holding the date and the absolute paths of its inputs; :func:`reproducible` replaces it
by a fixed line naming the tool, its version and the script that ran it, so the same sources give
the same bytes on any machine and any day.
"""
from __future__ import annotations

import pathlib
import re
import subprocess
import sys

import sumo

SUMO_HOME = pathlib.Path(sumo.SUMO_HOME)
BIN = SUMO_HOME / "bin"
TOOLS = SUMO_HOME / "tools"
_HEADER = re.compile(r"<!-- generated on .*? by Eclipse SUMO (\S+(?: \S+)*?) v?(\d+\.\d+\.\d+)\n.*?-->\n", re.DOTALL)


def run(tool: str, args: list[str], cwd: pathlib.Path | None = None) -> None:
    """Run SUMO tool ``tool`` (a binary in SUMO's bin/ or a script path) quietly; on failure print
    its output and raise."""
    exe = [sys.executable, tool] if tool.endswith(".py") else [str(BIN / tool)]
    p = subprocess.run(exe + [str(a) for a in args], cwd=cwd, capture_output=True, text=True, check=False)
    if p.returncode != 0:
        sys.stderr.write(p.stdout + p.stderr)
        raise subprocess.CalledProcessError(p.returncode, exe + args)


def reproducible(path: pathlib.Path, made_by: str) -> pathlib.Path:
    """Replace SUMO's header comments (date, absolute paths; one per tool that wrote the file, e.g.
    randomTrips.py and duarouter) in ``path`` by fixed ones."""
    path.write_text(_HEADER.sub(lambda m: f"<!-- {m.group(1)} {m.group(2)}, {made_by} -->\n", path.read_text()))
    return path
