"""Rebuild the formation road case's net from its sources in scenarios/formation/src/.

Usage: python scenarios/formation/build.py     (needs the eclipse-sumo package: pip install -e .)

NAME.nod.xml + NAME.edg.xml -> NAME.net.xml with SUMO's netconvert, the options of
scenarios/roads/build.py; SUMO's dated header is replaced by a fixed line, so a rebuild from the
same sources is byte-identical.
"""
from __future__ import annotations

import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
SRC = HERE / "src"
sys.path.insert(0, str(HERE.parent))
import netbuild  # (scenarios/netbuild.py)
from roads.build import NETCONVERT_OPTIONS


def build(name: str, out_dir: pathlib.Path = HERE) -> pathlib.Path:
    out = pathlib.Path(out_dir).resolve() / f"{name}.net.xml"
    args = ["--node-files", f"{name}.nod.xml", "--edge-files", f"{name}.edg.xml", "--output-file", out]
    netbuild.run("netconvert", args + NETCONVERT_OPTIONS, cwd=SRC)
    return netbuild.reproducible(out, f"scenarios/formation/build.py from src/{name}.*.xml")


def main(argv: list[str]) -> int:
    for name in argv or sorted({p.name.split(".")[0] for p in SRC.glob("*.nod.xml")}):
        print(f"built {build(name).relative_to(HERE.parent.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
