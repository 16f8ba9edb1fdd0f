"""The bad-input corpus's shared parts: good base files, the case type and the check every case
must pass (exit code 2, one stderr line naming the file and the key or flag, no traceback,
nothing written)."""
from __future__ import annotations

import dataclasses
import os
import pathlib
import subprocess
import sys

from conftest import ROOT, cli_in_process

NET = ROOT / "nets" / "overtaking.net.xml"
ROUTES = ROOT / "scenarios" / "overtaking.rou.xml"
CL = "<command line>"


def base(extra: str = "", *, sim: str = "", ego: str = "", net=NET, routes=(ROUTES,), ids='["ego"]') -> str:
    """A good 3 s scenario on the overtaking road, absolute paths, with extra lines put in."""
    rou = ", ".join(f'"{r}"' for r in routes)
    return (f'name = "bad"\n[sim]\nnet = "{net}"\nroutes = [{rou}]\nduration_s = 3.0\n{sim}\n'
            f'[ego]\nids = {ids}\n{ego}\n{extra}\n')


@dataclasses.dataclass
class Call:
    argv: list
    names: tuple  # what the one line must name (file, key or flag), each a substring
    cwd: pathlib.Path | None = None


@dataclasses.dataclass(frozen=True)
class Case:
    family: str
    make: object  # tmp_path -> Call
    sub: bool = False  # through a real process (reaches SUMO, or needs a process's own stdio)
    xfail: str | None = None


def scenario(text, key, *, files=None, extra_argv=(), cmd="run", sub=False, xfail=None) -> Case:
    """``sumo-avoid run S`` on a scenario file with ``text`` (bytes or str; ``{tmp}`` is the folder);
    the line must name S and ``key``."""
    def make(tmp):
        for name, content in (files or {}).items():
            _write(tmp / name, content, tmp)
        p = tmp / "s.toml"
        _write(p, text, tmp)
        argv = [cmd, p, *extra_argv] + (["--out", tmp / "out", "--quiet", "--no-plots"] if cmd == "run" else [])
        return Call(argv, (str(p), key), cwd=tmp)
    return Case("scenario" if not files else "sumo-inputs", make, sub, xfail)


def _write(path: pathlib.Path, content, tmp: pathlib.Path) -> None:
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content.replace("{tmp}", str(tmp)))


def tree(folder: pathlib.Path) -> dict:
    """Every path under ``folder`` with its size and modification time."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(folder):
        for n in dirnames + filenames:
            p = pathlib.Path(dirpath) / n
            st = p.lstat()
            out[str(p)] = (st.st_size, st.st_mtime_ns)
    return out


def check(case: Case, tmp: pathlib.Path) -> None:
    call = case.make(tmp)
    before = tree(tmp)
    if case.sub:
        p = subprocess.run([sys.executable, "-m", "sumo_avoid.cli", *map(str, call.argv)], capture_output=True, check=False,
                           text=True, cwd=call.cwd, timeout=120)
        rc, err = p.returncode, p.stderr
    else:
        r = cli_in_process(*call.argv, cwd=call.cwd)
        rc, err = r.returncode, r.stderr
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("sumo-avoid: error: "), lines[0]
    for name in call.names:
        assert str(name) in lines[0], (name, lines[0])
    assert rc == 2, (rc, err)
    assert tree(tmp) == before, "something was written"
