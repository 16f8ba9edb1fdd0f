"""SUMO's input files checked before SUMO starts: what SUMO would refuse (or crash on) found up
front, with the file and the reason, so a bad scenario costs no simulation and no SUMO console.

:func:`check_inputs` parses the network and every route and additional file (C XML parser, each
file once per version) and checks what SUMO checks when it loads them: well-formed XML of the
right kind; the edges of an explicit route exist and follow each other (a connection in the net);
a trip's ``from``/``to``/``via`` edges exist; a vehicle's type and route are defined; a numeric
``departLane`` exists on its first edge. It does not route trips (SUMO does; an unroutable trip is
reported by SUMO when the run starts). Raises :class:`InputError` naming the file.
"""
from __future__ import annotations

import dataclasses
import functools
import gzip
import itertools
import os
import pathlib
import subprocess
import xml.etree.ElementTree as ET

import sumo as sumo_package  # eclipse-sumo: SUMO's programs beside libsumo

# SUMO's built-in vehicle types (usable without a <vType>)
DEFAULT_TYPES = frozenset({"DEFAULT_VEHTYPE", "DEFAULT_PEDTYPE", "DEFAULT_BIKETYPE", "DEFAULT_CONTAINERTYPE",
                           "DEFAULT_TAXITYPE", "DEFAULT_RAILTYPE"})
FLOCK_MAX_SPEED_MPS = 50.0  # top speed of the vehicle type SumoSim.add_free_vehicles gives an arena's flock
VEHICLES = ("vehicle", "trip", "flow")
# root elements of the route and additional files SUMO loads (<add>: the older name of <additional>)
ROUTE_ROOTS = ("routes", "additional", "add")


class InputError(ValueError):
    """A SUMO input file SUMO would refuse: ``path`` and ``reason`` (``element``: the vehicle, trip,
    flow or route it is about, as ``"vehicle 'ego'"``, or "")."""

    def __init__(self, path, reason: str, element: str = ""):
        self.path, self.reason, self.element = str(path), reason, element
        super().__init__(f"{path}: {element + ': ' if element else ''}{reason}")

    def __reduce__(self):
        return InputError, (self.path, self.reason, self.element)


@dataclasses.dataclass(frozen=True)
class NetInfo:
    lanes: dict  # normal edge id -> number of lanes
    connections: frozenset  # (from edge, to edge) pairs that a vehicle can drive


@dataclasses.dataclass(frozen=True)
class RouteInfo:
    types: frozenset  # vType and vTypeDistribution ids
    routes: dict  # route (and routeDistribution) id -> edges (() for a distribution)
    vehicles: tuple  # (tag, id, attrib, embedded route edges or None), in file order


def open_xml(path):
    """An input file opened for the XML parser; SUMO reads gzip-compressed files (``*.gz``) as well."""
    path = pathlib.Path(path)
    return gzip.open(path) if path.suffix == ".gz" else open(path, "rb")


def _parse(path: pathlib.Path, kinds: tuple[str, ...], what: str):
    """The root tag and the elements of an XML file; InputError if it is not (well-formed) XML of a kind."""
    try:
        with open_xml(path) as f:
            root = None
            items = []
            depth = 0
            for ev, el in ET.iterparse(f, events=("start", "end")):
                if ev == "start":
                    if root is None:
                        root = el.tag
                        if root not in kinds:
                            raise InputError(path, f"not a {what} file: its root element is <{root}>, "
                                                   f"expected <{'> or <'.join(kinds)}>")
                    depth += 1
                    continue
                depth -= 1
                items.append((el.tag, dict(el.attrib), depth, [c.attrib for c in el]))
                if depth <= 1:
                    el.clear()
    except ET.ParseError as e:
        raise InputError(path, f"not well-formed XML ({e})") from None
    except (OSError, EOFError, UnicodeDecodeError) as e:
        raise InputError(path, f"cannot be read ({e})") from None
    if root is None:
        raise InputError(path, f"not a {what} file (empty)")
    return items


@functools.lru_cache(maxsize=16)
def _net(path: str, mtime_ns: int, size: int) -> NetInfo:
    lanes, conns = {}, set()
    for tag, a, _, children in _parse(pathlib.Path(path), ("net",), "SUMO network"):
        if tag == "edge" and "id" in a and a.get("function", "normal") not in ("internal", "crossing", "walkingarea"):
            lanes[a["id"]] = sum(1 for c in children if "index" in c or "id" in c)
        elif tag == "connection" and "from" in a and "to" in a:
            conns.add((a["from"], a["to"]))
    if not lanes:
        raise InputError(path, "a SUMO network without edges")
    return NetInfo(lanes, frozenset(conns))


@functools.lru_cache(maxsize=64)
def _routes(path: str, mtime_ns: int, size: int) -> RouteInfo:
    types, routes, vehicles = set(), {}, []
    for tag, a, depth, children in _parse(pathlib.Path(path), ROUTE_ROOTS, "SUMO route or additional"):
        if tag in ("vType", "vTypeDistribution") and "id" in a:
            types.add(a["id"])
        elif tag == "routeDistribution" and "id" in a:
            routes[a["id"]] = ()
        elif tag == "route" and "id" in a and depth == 1:
            routes[a["id"]] = tuple(a.get("edges", "").split())
        elif tag in VEHICLES and "id" in a:
            inner = [c.get("edges", "").split() for c in children if "edges" in c]
            vehicles.append((tag, a["id"], a, tuple(inner[0]) if inner else None))
    return RouteInfo(frozenset(types), routes, tuple(vehicles))


def _stat_key(path) -> tuple[str, int, int]:
    st = pathlib.Path(path).stat()
    return str(path), st.st_mtime_ns, st.st_size


def read_net(path) -> NetInfo:
    return _net(*_stat_key(path))


def check_inputs(net, files) -> None:
    """Check a network and its route and additional ``files`` (in SUMO's loading order). Raises
    :class:`InputError` naming the file (and the element) of the first problem."""
    info = read_net(net)
    parsed = [(f, _routes(*_stat_key(f))) for f in files]
    types = set(DEFAULT_TYPES).union(*(r.types for _, r in parsed))
    routes = {k: v for _, r in parsed for k, v in r.routes.items()}
    for f, r in parsed:
        for rid, edges in r.routes.items():
            _check_path(f, info, edges, f"route '{rid}'", net)
        for tag, vid, a, inner in r.vehicles:
            what = f"{tag} '{vid}'"
            if a.get("type", "DEFAULT_VEHTYPE") not in types:
                raise InputError(f, f"its type '{a['type']}' is not defined (no <vType> of that id)", what)
            if "route" in a and a["route"] not in routes:
                raise InputError(f, f"its route '{a['route']}' is not defined", what)
            for key in ("from", "to"):  # SUMO trims the ids ('to="E1 "': Wildau's counted flows)
                if key in a and a[key].strip() not in info.lanes:
                    raise InputError(f, f"its {key} edge '{a[key]}' is not in the network {net}", what)
            for e in a.get("via", "").split():
                if e not in info.lanes:
                    raise InputError(f, f"its via edge '{e}' is not in the network {net}", what)
            edges = inner if inner is not None else routes.get(a.get("route"), ()) or ((a["from"].strip(),) if "from" in a else ())
            if inner is not None:
                _check_path(f, info, inner, what, net)
            lane = a.get("departLane", "")
            if lane.isdigit() and edges and edges[0] in info.lanes and int(lane) >= info.lanes[edges[0]]:
                raise InputError(f, f"departLane {lane} does not exist: edge '{edges[0]}' has "
                                    f"{info.lanes[edges[0]]} lane(s)", what)


def _check_path(f, info: NetInfo, edges, what: str, net) -> None:
    for e in edges:
        if e not in info.lanes:
            raise InputError(f, f"its edge '{e}' is not in the network {net}", what)
    for a, b in itertools.pairwise(edges):
        if (a, b) not in info.connections:
            raise InputError(f, f"edges '{a}' and '{b}' are not connected in the network {net}", what)


def depart_times(files) -> dict[str, float]:
    """vehicle/trip id -> numeric depart time, s (flows and non-numeric departs left out)."""
    out = {}
    for f in files:
        for tag, vid, a, _ in _routes(*_stat_key(f)).vehicles:
            try:
                if tag != "flow":
                    out[vid] = float(a.get("depart", "0"))
            except ValueError:  # "triggered", "now", ...
                pass
    return out


def sumo_binary() -> pathlib.Path:
    """SUMO's own ``sumo`` program, of the release libsumo is built from (the eclipse-sumo wheel)."""
    return pathlib.Path(sumo_package.SUMO_HOME) / "bin" / "sumo"


def sumo_env() -> dict:
    return {**os.environ, "SUMO_HOME": sumo_package.SUMO_HOME}


def refused_file(net, additional=(), routes=()) -> pathlib.Path | None:
    """Which file SUMO refused when it would not start and its message names none: the first of the
    additional files, then the route files (SUMO's load order) that SUMO's own ``sumo`` program refuses
    with the net and the files before it; None if none is refused alone or there is no ``sumo`` program.
    Only after a failed start: each try loads the net again."""
    binary = sumo_binary()
    files = [("-a", pathlib.Path(f)) for f in additional] + [("-r", pathlib.Path(f)) for f in routes]
    for k, (_, f) in enumerate(files):
        args = [str(binary), "-n", str(net), "--end", "0", "--no-step-log", "true", "--no-warnings", "true"]
        for flag in ("-a", "-r"):
            chosen = [str(g) for fl, g in files[:k + 1] if fl == flag]
            args += [flag, ",".join(chosen)] if chosen else []
        try:
            rc = subprocess.run(args, capture_output=True, timeout=300,
                                env=sumo_env()).returncode
        except (OSError, subprocess.SubprocessError):
            return None
        if rc != 0:
            return f
    return None
