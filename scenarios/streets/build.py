"""Rebuild every net of the streets scenario library from its plain-XML sources in scenarios/streets/src/.

Usage: python scenarios/streets/build.py [NAME...]          rebuild NAME.net.xml here (all nets by default)
       python scenarios/streets/build.py --check [NAME...]  rebuild into a temporary folder and compare
                                                            byte for byte with the committed nets (exit 1
                                                            naming each net that differs)
(needs the eclipse-sumo package: pip install -e .)

NAME.nod.xml + NAME.edg.xml (+ NAME.typ.xml lane types, NAME.con.xml connections and crossings,
NAME.tll.xml signal programs) -> NAME.net.xml with SUMO's netconvert: plain XML, geometry in metres,
no projection, coordinates kept as written (the options below, as for scenarios/roads/build.py).
Sidewalks, bike and bus lanes are lanes with vehicle-class permissions in the types; walking areas
are built by netconvert wherever a node has a crossing.

The header SUMO writes (date, absolute paths) is replaced by a fixed line, so a rebuild from the
same sources is byte-identical.
"""
from __future__ import annotations

import pathlib
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
SRC = HERE / "src"
sys.path.insert(0, str(HERE.parent))
import netbuild  # (scenarios/netbuild.py, shared with scenarios/roads/build.py)

NETCONVERT_OPTIONS = ["--no-internal-links", "false", "--junctions.corner-detail", "5", "--no-turnarounds", "true",
                      "--offset.disable-normalization", "true", "--output.street-names", "false"]
# optional sources beside NAME.nod.xml and NAME.edg.xml: suffix -> netconvert option
OPTIONAL = {"typ": "--type-files", "con": "--connection-files", "tll": "--tllogic-files"}


def names() -> list[str]:
    return sorted(p.name.split(".")[0] for p in SRC.glob("*.nod.xml"))


def build(name: str, out_dir: pathlib.Path = HERE) -> pathlib.Path:
    """netconvert src/NAME.* into out_dir/NAME.net.xml with a fixed header; returns that path."""
    out = pathlib.Path(out_dir).resolve() / f"{name}.net.xml"
    args = ["--node-files", f"{name}.nod.xml", "--edge-files", f"{name}.edg.xml", "--output-file", out]
    for suffix, option in OPTIONAL.items():
        if (SRC / f"{name}.{suffix}.xml").exists():
            args += [option, f"{name}.{suffix}.xml"]
    netbuild.run("netconvert", args + NETCONVERT_OPTIONS, cwd=SRC)
    return netbuild.reproducible(out, f"scenarios/streets/build.py from src/{name}.*.xml")


def check(selected: list[str]) -> list[str]:
    """The names among ``selected`` whose rebuild differs from the committed net (or that has none)."""
    with tempfile.TemporaryDirectory() as tmp:
        return [n for n in selected if not (HERE / f"{n}.net.xml").exists()
                or build(n, pathlib.Path(tmp)).read_bytes() != (HERE / f"{n}.net.xml").read_bytes()]


def main(argv: list[str]) -> int:
    if argv[:1] == ["--check"]:
        selected = argv[1:] or names()
        differ = check(selected)
        for n in differ:
            print(f"scenarios/streets/{n}.net.xml: differs from a rebuild of src/{n}.*.xml")
        if not differ:
            print(f"{len(selected)} nets rebuilt byte-identically")
        return 1 if differ else 0
    for name in argv or names():
        print(f"built {build(name).relative_to(HERE.parent.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
