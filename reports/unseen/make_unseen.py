"""Build six netgenerate nets the project was never tuned on (more lanes, more traffic than the generated
suite), with the generated suite's own builder (scenarios/generated/make.py: randomTrips traffic, an ego
route through >= 3 junctions, a scenario file per net), into a folder of your choice.

Usage:  python reports/unseen/make_unseen.py OUT_DIR
then    sumo-avoid batch OUT_DIR/*/scenario.toml --seeds 1-2 --workers 2 --ledger OUT_DIR/truth.sqlite
        (and the same with --set ego.sensor=radar)
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "scenarios" / "generated"))
import make  # noqa: E402

make.INSERTION_DENSITY = 450.0  # vehicles per hour and km of lane (the generated suite: 300)
NETS = {  # the number is netgenerate's and randomTrips.py's seed
    "grid31": make._grid(4, 4, 150, 3) + make.TLS,  # 3 lanes each way, static lights
    "grid32": make._grid(4, 3, 200, 2) + make.TLS + ["--tls.default-type", "actuated"],
    "rand33": make._rand(40, 2) + make.TLS,
    "grid34": make._grid(3, 4, 180, 3),  # priority junctions
    "rand35": make._rand(50, 3),
    "spider36": make._spider(6, 3, 60, 2) + make.TLS,
}

def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="build the six unseen nets into OUT_DIR")
    ap.add_argument("out", type=pathlib.Path, metavar="OUT_DIR")
    out = ap.parse_args(argv).out  # a missing OUT_DIR: argparse's one line, exit 2
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:  # bad input: one line, exit 2, nothing written
        print(f"make_unseen: error: OUT_DIR {out}: {e.strerror}", file=sys.stderr)
        return 2
    make.NETS.update(NETS)
    for name in NETS:
        print(name, make.build_one(name, out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
