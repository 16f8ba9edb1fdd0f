"""What each city scenario's ego route crosses, read from the district's net with sumolib.

    python scenarios/cities/routes.py                 # every scenario in scenarios/cities/
    python scenarios/cities/routes.py wildau_turns    # one

A junction here is a node the route passes (the end of every edge but its last) that is signalised, a level
crossing of a railway, or where at least three roads a passenger car may use meet; nodes that only join two
pieces of one road (OSM geometry) are not counted. Per junction: its type, how the route leaves it (SUMO's
link direction: s straight, r/l right/left, R/L partly right/left, t turn), the pedestrian crossings there
and the bus-only lanes beside the ego's lane on the edge into it. tests/scenario/test_cities_suite.py checks
each route with :func:`junctions`.
"""
from __future__ import annotations

import pathlib
import sys
import tomllib
import xml.etree.ElementTree as ET

import sumolib

HERE = pathlib.Path(__file__).resolve().parent


def ego_route(scenario: pathlib.Path) -> tuple[pathlib.Path, list[str]]:
    """(the net file, the ego's route edges) of a city scenario: the last route file holds the ego."""
    sim = tomllib.loads(scenario.read_text())["sim"]
    cfg = (scenario.parent / sim["sumocfg"]).resolve()
    net = cfg.parent / ET.parse(cfg).getroot().find("input/net-file").get("value")
    ego, = [v for v in ET.parse(scenario.parent / sim["routes"][-1]).getroot().iter("vehicle") if v.get("id") == "ego"]
    return net, ego.find("route").get("edges").split()


def read_net(path: pathlib.Path):
    return sumolib.net.readNet(str(path), withInternal=True, withPedestrianConnections=True)


def _car_arms(node) -> int:
    ends = {e.getFromNode().getID() for e in node.getIncoming() if e.getFunction() == "" and e.allows("passenger")}
    ends |= {e.getToNode().getID() for e in node.getOutgoing() if e.getFunction() == "" and e.allows("passenger")}
    return len(ends)


def junctions(net, edges: list[str]) -> list[dict]:
    """The junctions the route passes, in order (see the module's docstring); raises KeyError for an edge the
    net does not have and ValueError where no car link joins two consecutive edges."""
    path = [net.getEdge(e) for e in edges]
    out, dist = [], 0.0
    for a, b in zip(path, path[1:]):
        dist += a.getLength()
        links = [c for c in a.getOutgoing().get(b, []) if c.getFromLane().allows("passenger")
                 and c.getToLane().allows("passenger")]
        if not links:
            raise ValueError(f"no car link from edge {a.getID()} to {b.getID()}")
        node = a.getToNode()
        kind = node.getType()
        if "traffic_light" not in kind and kind != "rail_crossing" and _car_arms(node) < 3:
            continue
        crossings = {x.getID() for x in node.getIncoming() + node.getOutgoing() if x.getFunction() == "crossing"}
        bus = [ln for ln in a.getLanes() if ln.allows("bus") and not ln.allows("passenger")]
        out.append({"node": node.getID(), "type": kind, "at_m": round(dist), "arms": _car_arms(node),
                    "turn": "".join(sorted({c.getDirection() for c in links})),
                    "signalised": "traffic_light" in kind, "crossings": len(crossings), "bus_lanes": len(bus)})
    return out


def bus_edges(net, edges: list[str]) -> int:
    """How many of the route's edges have a bus-only lane."""
    return sum(any(ln.allows("bus") and not ln.allows("passenger") for ln in net.getEdge(e).getLanes()) for e in edges)


def length_m(net, edges: list[str]) -> float:
    return sum(net.getEdge(e).getLength() for e in edges)


def main(names: list[str]) -> int:
    paths = [HERE / f"{n}.toml" for n in names] if names else sorted(HERE.glob("*.toml"))
    for p in paths:
        if not p.is_file():
            print(f"routes.py: no city scenario {p.name} in {HERE}", file=sys.stderr)
            return 2
    nets = {}
    for p in paths:
        net_file, edges = ego_route(p)
        if net_file not in nets:
            nets[net_file] = read_net(net_file)
        net = nets[net_file]
        js = junctions(net, edges)
        print(f"{p.stem}: {len(edges)} edges, {length_m(net, edges):.0f} m, {len(js)} junctions, "
              f"{sum(j['signalised'] for j in js)} signalised, crossings at {sum(j['crossings'] > 0 for j in js)}, "
              f"a bus-only lane beside on {bus_edges(net, edges)} edges")
        for j in js:
            print(f"    {j['at_m']:5d} m  {j['node'][:44]:44s} {j['type']:17s} arms {j['arms']}  turn {j['turn']:3s} "
                  f"crossings {j['crossings']:2d}  bus-only lanes before {j['bus_lanes']}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
