"""Builds the unseen-net flock check (issue 14 item 9): a net the flocking controller was not tuned
on, made by SUMO's netgenerate (a 5-arm, 3-circle spider, two lanes each way), background traffic
from SUMO's randomTrips.py (fixed seed, routed by duarouter), and a flock of six egos whose route
turns at five junctions (right onto a circle, left onto an arm, through the centre, out another arm).

    python scenarios/flock_unseen/build.py     # writes spider.net.xml and traffic.rou.xml here
"""
from __future__ import annotations

import pathlib
import subprocess
import sys

import sumo

HERE = pathlib.Path(__file__).resolve().parent
BIN = pathlib.Path(sumo.SUMO_HOME) / "bin"
TOOLS = pathlib.Path(sumo.SUMO_HOME) / "tools"


def main() -> None:
    net, traffic = HERE / "spider.net.xml", HERE / "traffic.rou.xml"
    subprocess.run([str(BIN / "netgenerate"), "--spider", "--spider.arm-number", "5", "--spider.circle-number", "3",
                    "--spider.space-radius", "80", "--default.lanenumber", "2", "--default.speed", "16.67",
                    "--no-turnarounds", "true", "--seed", "1", "--output.street-names", "false",
                    "-o", str(net)], check=True, capture_output=True)
    subprocess.run([sys.executable, str(TOOLS / "randomTrips.py"), "-n", str(net), "-r", str(traffic),
                    "-o", str(HERE / "trips.xml"), "--seed", "7", "--begin", "0", "--end", "90", "--period", "3",
                    "--fringe-factor", "5", "--min-distance", "200", "--prefix", "bg", "--validate"],
                   check=True, capture_output=True)
    (HERE / "trips.xml").unlink(missing_ok=True)
    for f in (net, traffic):  # SUMO's header comment names the date and this machine's paths
        text = f.read_text()
        start = text.find("<!--")
        f.write_text(text[:start] + "<!-- built by scenarios/flock_unseen/build.py -->" + text[text.find("-->", start) + 3:])
    for f in HERE.glob("*.alt.xml"):
        f.unlink()


if __name__ == "__main__":
    main()
