"""Rebuild every net of the road scenario library from its sources in scenarios/roads/src/.

Usage: python scenarios/roads/build.py [NAME...]     (needs the eclipse-sumo package: pip install -e .)

* NAME.nod.xml + NAME.edg.xml (+ NAME.con.xml) -> NAME.net.xml with SUMO's netconvert (plain XML,
  geometry in metres, no projection; the options below, as for nets/build.py);
* NAME.netgcfg (a netgenerate configuration file) -> NAME.net.xml with SUMO's netgenerate.

The header SUMO writes (date, absolute paths) is replaced by a fixed line, so a rebuild from the
same sources is byte-identical.
"""
from __future__ import annotations

import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
SRC = HERE / "src"
sys.path.insert(0, str(HERE.parent))
import netbuild  # (scenarios/netbuild.py, shared with scenarios/generated/make.py)

NETCONVERT_OPTIONS = ["--no-internal-links", "false", "--junctions.corner-detail", "5", "--no-turnarounds", "true",
                      "--offset.disable-normalization", "true", "--output.street-names", "false"]


def names() -> list[str]:
    return sorted({p.name.split(".")[0] for p in SRC.iterdir() if p.name.endswith((".nod.xml", ".netgcfg"))})


def build(name: str, out_dir: pathlib.Path = HERE) -> pathlib.Path:
    out = pathlib.Path(out_dir).resolve() / f"{name}.net.xml"
    cfg = SRC / f"{name}.netgcfg"
    if cfg.exists():
        netbuild.run("netgenerate", ["-c", cfg.name, "--output-file", out], cwd=SRC)
        return netbuild.reproducible(out, f"scenarios/roads/build.py from src/{cfg.name}")
    args = ["--node-files", f"{name}.nod.xml", "--edge-files", f"{name}.edg.xml", "--output-file", out]
    if (SRC / f"{name}.con.xml").exists():
        args += ["--connection-files", f"{name}.con.xml"]
    netbuild.run("netconvert", args + NETCONVERT_OPTIONS, cwd=SRC)
    return netbuild.reproducible(out, f"scenarios/roads/build.py from src/{name}.*.xml")


def main(argv: list[str]) -> int:
    for name in argv or names():
        print(f"built {build(name).relative_to(HERE.parent.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
