"""Rebuild the planner's road net from its sources in scenarios/planner/src/ (SUMO's netconvert).

Usage: python scenarios/planner/build.py          (needs the eclipse-sumo package: pip install -e .)

road.nod.xml + road.edg.xml -> road.net.xml, with the options of scenarios/roads/build.py; SUMO's
dated header is replaced by a fixed line, so a rebuild from the same sources is byte-identical.
"""
from __future__ import annotations

import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import netbuild  # (scenarios/netbuild.py)
from roads.build import NETCONVERT_OPTIONS


def build(name: str = "road", out_dir: pathlib.Path = HERE) -> pathlib.Path:
    out = pathlib.Path(out_dir).resolve() / f"{name}.net.xml"
    args = ["--node-files", f"{name}.nod.xml", "--edge-files", f"{name}.edg.xml", "--output-file", out]
    netbuild.run("netconvert", args + NETCONVERT_OPTIONS, cwd=HERE / "src")
    return netbuild.reproducible(out, f"scenarios/planner/build.py from src/{name}.*.xml")


if __name__ == "__main__":
    print(f"built {build().relative_to(HERE.parent.parent)}")
