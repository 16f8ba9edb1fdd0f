"""Rebuild every network in nets/ from its plain-XML sources in nets/src/ with SUMO's netconvert.

Usage: python nets/build.py        (needs the eclipse-sumo package: pip install -e .)

Each NAME.nod.xml (+ NAME.edg.xml, optional NAME.con.xml) becomes nets/NAME.net.xml.
Internal links are always on; the geometry is given in metres (no projection, so the
networks carry a <location> element with offset 0 and SUMO's own x/y coordinates).
"""
from __future__ import annotations

import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
SRC = HERE / "src"


def netconvert_binary() -> str:
    try:
        import sumo  # the eclipse-sumo wheel

        return str(pathlib.Path(sumo.SUMO_HOME) / "bin" / "netconvert")
    except ImportError:  # pragma: no cover - fall back to PATH
        return "netconvert"


def build(name: str) -> pathlib.Path:
    out = HERE / f"{name}.net.xml"
    cmd = [
        netconvert_binary(),
        "--node-files", str(SRC / f"{name}.nod.xml"),
        "--edge-files", str(SRC / f"{name}.edg.xml"),
        "--output-file", str(out),
        "--no-internal-links", "false",
        "--junctions.corner-detail", "5",
        "--no-turnarounds", "true",
        "--offset.disable-normalization", "true",
        "--output.street-names", "false",
    ]
    con = SRC / f"{name}.con.xml"
    if con.exists():
        cmd += ["--connection-files", str(con)]
    subprocess.run(cmd, check=True)
    return out


def main(argv: list[str]) -> int:
    names = argv or sorted(p.name[: -len(".nod.xml")] for p in SRC.glob("*.nod.xml"))
    for name in names:
        print(f"built {build(name)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
