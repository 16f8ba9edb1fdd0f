"""Real runs to watch: crash_straight (the ego drives blind into a parked car at 5.7 s), made once
per test process with ``sumo-avoid run`` (the fixture ``crash_run``: import it into a test module);
and the tools that open them (Debian's chromium, Xvfb)."""
from __future__ import annotations

import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def run_dir(factory, name: str, *extra: str) -> pathlib.Path:
    from sumo_avoid.cli import main

    out = factory.mktemp(name) / "run"
    assert main(["run", str(ROOT / "scenarios" / f"{name}.toml"), "--out", str(out), "--no-plots", "--quiet",
                 *extra]) == 0
    return out


_MADE: dict = {}


@pytest.fixture()
def crash_run(tmp_path_factory) -> pathlib.Path:
    """The crash_straight run, made once per test process and shared by the test modules importing this."""
    if "crash" not in _MADE:
        _MADE["crash"] = run_dir(tmp_path_factory, "crash_straight")
    return _MADE["crash"]


def tool(*names: str, why: str) -> str:
    """The first of ``names`` on PATH; the test is skipped, saying so, where none is installed."""
    for n in names:
        found = shutil.which(n)
        if found:
            return found
    pytest.skip(f"{' / '.join(names)} is not installed ({why}; .ci/run installs it with apt-get)")
