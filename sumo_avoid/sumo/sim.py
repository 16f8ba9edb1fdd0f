"""The one module that talks to libsumo.

:class:`SumoSim` starts SUMO for a scenario, reads the world once per step into an immutable
:class:`~sumo_avoid.core.snapshot.Snapshot` (through subscriptions, not per-vehicle getters; positions
in 3-D, the z for :mod:`sumo_avoid.core.levels`), applies the actuator's poses to the egos with
``moveToXY`` (on their route's lanes while they drive on them, :mod:`sumo_avoid.sumo.placement`) and advances it.

SUMO runs with a fixed seed, ``--collision.check-junctions``, collisions reported but not acted on
(``--collision.action warn``, ``--collision.mingap-factor 0`` = physical contact only), no
teleporting, and the sublane model. Egos run with SUMO's safety checks off (speed mode 32,
lane-change mode 0), so a controller's mistakes are not hidden; other vehicles keep SUMO's models,
and so do egos left to SUMO's driver (controller ``sumo``: taken over with ``drive=False``, never moved).
"""
from __future__ import annotations

import itertools
import math
import pathlib
from dataclasses import dataclass

import libsumo
import numpy as np

from sumo_avoid.core.snapshot import Snapshot
from sumo_avoid.core.types import EgoTask
from sumo_avoid.sumo.console import first_error, native_stderr_kept, start_error
from sumo_avoid.sumo.inputs import FLOCK_MAX_SPEED_MPS
from sumo_avoid.sumo.placement import RoutePlacement
from sumo_avoid.sumo.road_users import RoadUsers
from sumo_avoid.sumo.ssm_device import SsmRequest, equip, ssm_args

_DYNAMIC = (libsumo.constants.VAR_POSITION3D, libsumo.constants.VAR_ANGLE, libsumo.constants.VAR_SPEED,
            libsumo.constants.VAR_LANE_ID, libsumo.constants.VAR_LANEPOSITION)
_PERSON = _DYNAMIC + (libsumo.constants.VAR_VEHICLE,)
_SIM_VARS = (libsumo.constants.VAR_DEPARTED_VEHICLES_IDS, libsumo.constants.VAR_ARRIVED_VEHICLES_IDS,
             libsumo.constants.VAR_DEPARTED_PERSONS_IDS, libsumo.constants.VAR_ARRIVED_PERSONS_IDS)
#: libsumo gives a vehicle moved off every lane (an arena's flock) a 3-D position without z: z = 0
_NO_Z = {2: (0.0,), 3: ()}
EGO_SPEED_MODE = 32  # all of SUMO's speed safety checks off (verified: a commanded crash happens)
EGO_LANE_CHANGE_MODE = 0  # SUMO changes no lanes for the ego: the plug-in is in charge


@dataclass(frozen=True)
class SumoCollision:
    time_s: float
    collider: str
    victim: str
    kind: str
    lane: str


@dataclass(frozen=True)
class EgoInfo:
    """What the plug-in learns about an ego when it takes it over."""

    vid: str
    route_edges: tuple[str, ...]
    lane_index: int
    width_m: float = 1.8
    length_m: float = 5.0
    vclass: str = "passenger"  # SUMO vehicle class of its type


def sumo_args(net: pathlib.Path, routes, additional, step_s: float, seed: int, lateral_resolution_m: float,
              log_file: pathlib.Path | None, sumo_collisions: bool = True, ssm: SsmRequest | None = None,
              begin_s: float = 0.0, options=()) -> list[str]:
    """SUMO's command line. ``sumo_collisions=False`` turns SUMO's own (lane-based) collision check
    off: for a flock moved off-lane anywhere in an arena it reports tens of thousands of spurious
    contacts per run (measured); the plug-in's footprint check is the reference there. ``ssm``
    equips the named egos, and only them, with SUMO's SSM device (:mod:`sumo_avoid.sumo.ssm_device`): the
    route and additional files defining an ego are replaced by equipped copies in its folder. ``begin_s``:
    SUMO's ``--begin``; ``options``: more (name, value) pairs of SUMO's options (``sim.options``, a
    ``.sumocfg``'s options the plug-in does not own), given before the plug-in's own."""
    if ssm is not None and ssm.ego_ids:
        routes, additional = equip(routes or (), ssm, "r"), equip(additional or (), ssm, "a")
    args = ["sumo", *(a for name, value in options for a in (f"--{name}", value)), "-n", str(net), "--step-length", repr(step_s), "--seed", str(seed),
            "--collision.action", "warn" if sumo_collisions else "none",
            "--collision.check-junctions", "true" if sumo_collisions else "false",
            "--collision.mingap-factor", "0", "--lateral-resolution", repr(lateral_resolution_m),
            "--time-to-teleport", "-1", "--no-step-log", "true", "--duration-log.disable", "true"]
    if begin_s:
        args += ["--begin", repr(begin_s)]
    if routes:
        args += ["-r", ",".join(str(r) for r in routes)]
    if additional:
        args += ["-a", ",".join(str(a) for a in additional)]
    if ssm is not None:
        args += ssm_args(ssm)
    if log_file is not None:
        args += ["--log", str(log_file)]
    else:
        args += ["--no-warnings", "true"]
    return args


class SumoStartError(RuntimeError):
    """SUMO refused to load the network, routes or additional files."""


class SumoStepError(RuntimeError):
    """SUMO stopped on the scenario's input in a step (e.g. an invalid departLane, found only at insertion)."""


class SumoSim:
    """One running SUMO (libsumo allows one per process: parallel runs need processes)."""

    def __init__(self, args: list[str]):
        if libsumo.isLoaded():
            raise RuntimeError("a libsumo simulation is already running in this process")
        with native_stderr_kept() as said:
            try:
                libsumo.start(args)
                refused = None
            except Exception as e:  # libsumo raises TraCIException / FatalTraCIError on bad input
                refused = e
                if libsumo.isLoaded():
                    libsumo.close()
        if refused is not None:  # SUMO's own first error line says why (libsumo's may say only "Process Error")
            raise SumoStartError(start_error(first_error("".join(said)), " ".join(str(refused).split()))) from None
        self.step_s = libsumo.simulation.getDeltaT()
        self.apart: dict = {}  # edges crossing without a junction (road.grade), given to every snapshot; set by the runner
        libsumo.simulation.subscribe(list(_SIM_VARS))
        self._users = RoadUsers(libsumo.vehicle, libsumo.person, _DYNAMIC, _PERSON)  # who is subscribed (sumo.road_users)
        self._no_pose: set[str] = set()  # road users SUMO gave a non-finite position (noted once, _finite)
        self._egos: set[str] = set()
        self._applied: dict[str, float] = {}  # ego -> the signed speed it was last moved at (see read)
        self._routes: dict[str, tuple[str, ...]] = {}  # ego -> its route as SUMO gave it at take-over
        self._placement = RoutePlacement()
        self._arrived: frozenset[str] = frozenset()  # vehicles SUMO took out at their route's end in the last step
        self._static_key: tuple[str, ...] | None = None  # read(): libsumo's ids the cached static part is for
        self._static: tuple = ()
        self._users.add(libsumo.vehicle.getIDList(), libsumo.person.getIDList())
        self._stepped = False  # libsumo keeps a previous run's subscription results until the first step
        for tls in libsumo.trafficlight.getIDList():  # every signal's state, read with the vehicles
            libsumo.trafficlight.subscribe(tls, [libsumo.constants.TL_RED_YELLOW_GREEN_STATE])

    # --- reading ---------------------------------------------------------------------------
    @property
    def world_before_egos(self) -> bool:
        """Does :meth:`read` give the whole world before the first ego is taken over? (True by default. False: only
        the signals, and no road user is subscribed before it (:mod:`sumo_avoid.sumo.road_users`), when nothing read
        then is used: a recording of the road users near egos.)"""
        return not self._users.defer

    @world_before_egos.setter
    def world_before_egos(self, whole: bool) -> None:
        if whole or self._routes:  # (an ego taken over already)
            self._users.start()  # (subscribes to whoever departed while it deferred)
        else:
            self._users.defer = True

    def read(self) -> Snapshot:
        """The world now, as an immutable snapshot (centres, math headings); empty before the first step."""
        if not self._stepped:
            return Snapshot.empty(self.time_s, {})
        if self._users.defer:
            return Snapshot.empty(self.time_s, self._signals())
        res = libsumo.vehicle.getAllSubscriptionResults()
        key = tuple(res)
        if key != self._static_key:  # ids, lengths, widths, ego flags, rows only change with the vehicle set
            dims_of = self._users.dims
            ids = tuple(v for v in key if v in dims_of)  # the vehicles this run subscribed
            self._static_key = key
            self._static = (ids, np.array([dims_of[v] for v in ids], dtype=float).reshape(-1, 2),
                            np.array([v in self._egos for v in ids], dtype=bool), tuple(self._users.vclass[v] for v in ids))
        ids, dims, is_ego, vclass = self._static
        n = len(ids)
        signals = self._signals()
        persons = self._read_persons() if self._users.persons else None
        if n == 0 and persons is None:
            return Snapshot.empty(self.time_s, signals)
        rows = res.values() if n == len(key) else [res[v] for v in ids]
        c = libsumo.constants
        P, A, S, LP = c.VAR_POSITION3D, c.VAR_ANGLE, c.VAR_SPEED, c.VAR_LANEPOSITION
        flat = np.fromiter(itertools.chain.from_iterable((*r[P], *_NO_Z[len(r[P])], r[A], r[S], r[LP]) for r in rows),
                           float, 6 * n)
        flat = flat.reshape(n, 6)  # front bumper x, y, z, compass angle (deg), speed, lane position
        keep = self._finite(flat, ids, is_ego)
        if keep is not None:
            rows = [r for r, k in zip(rows, keep) if k]
            ids, dims, is_ego, vclass = (tuple(itertools.compress(ids, keep)), dims[keep], is_ego[keep],
                                         tuple(itertools.compress(vclass, keep)))
            flat, n = flat[keep], int(keep.sum())
        z, flat = flat[:, 2], flat[:, [0, 1, 3, 4, 5]]
        lane = tuple(r[c.VAR_LANE_ID] for r in rows)
        heading = np.radians(90.0 - flat[:, 2])
        direction = np.column_stack([np.cos(heading), np.sin(heading)])
        centre = flat[:, :2] - direction * (dims[:, :1] / 2.0)
        if self._applied:  # an ego moves at the speed the plug-in applied: SUMO keeps a moved vehicle's speed
            # >= 0 (an ego backing up moves against its heading) and reads it as 0 at some edge changes
            # (rand08: 0 m/s on entering a junction's internal lane while it moved at 2.5 m/s)
            mine = [(k, self._applied[v]) for k, v in enumerate(ids) if v in self._applied]
            if mine:
                rows_e, v_e = zip(*mine)
                flat[list(rows_e), 3] = np.asarray(v_e, float) + 0.0  # (+ 0.0: no -0.0 in the recording)
        lane_pos = np.where([bool(x) for x in lane], flat[:, 4], np.nan)
        vel, length, width, person = direction * flat[:, 3:4], dims[:, 0], dims[:, 1], np.zeros(n, bool)
        if persons is not None:
            p_ids, p_centre, p_vel, p_heading, p_dims, p_lane, p_lane_pos, p_z = persons
            z = np.concatenate([z, p_z])
            ids, lane, vclass = ids + p_ids, lane + p_lane, vclass + ("pedestrian",) * len(p_ids)
            centre, vel = np.concatenate([centre, p_centre]), np.concatenate([vel, p_vel])
            heading = np.concatenate([heading, p_heading])
            length, width = np.concatenate([length, p_dims[:, 0]]), np.concatenate([width, p_dims[:, 1]])
            is_ego, person = np.concatenate([is_ego, np.zeros(len(p_ids), bool)]), np.r_[person, np.ones(len(p_ids), bool)]
            lane_pos = np.concatenate([lane_pos, p_lane_pos])
        return Snapshot(self.time_s, ids, centre, vel, heading, length, width, is_ego, signals=signals, lane=lane,
                        lane_pos=lane_pos, vclass=vclass, is_person=person, z=z, apart=self.apart)

    def _read_persons(self):
        """Persons outside vehicles: ids, centres, velocities, headings, (length, width), lanes, lane positions,
        heights; None when there are none. A person's SUMO position is its front, like a vehicle's."""
        c = libsumo.constants
        res = libsumo.person.getAllSubscriptionResults()
        rows = [(pid, r) for pid, r in res.items() if pid in self._users.persons and not r[c.VAR_VEHICLE]]
        if not rows:
            return None
        m = len(rows)
        P = c.VAR_POSITION3D
        flat = np.fromiter(itertools.chain.from_iterable((*r[P], *_NO_Z[len(r[P])], r[c.VAR_ANGLE], r[c.VAR_SPEED],
                                                          r[c.VAR_LANEPOSITION]) for _, r in rows), float, 6 * m)
        flat = flat.reshape(m, 6)
        keep = self._finite(flat, (pid for pid, _ in rows))
        if keep is not None:
            rows, flat, m = list(itertools.compress(rows, keep)), flat[keep], int(keep.sum())
            if not m:
                return None
        z, flat = flat[:, 2], flat[:, [0, 1, 3, 4, 5]]
        p_ids = tuple(pid for pid, _ in rows)
        dims = np.array([self._users.persons[pid] for pid in p_ids], float).reshape(m, 2)
        heading = np.radians(90.0 - flat[:, 2])
        direction = np.column_stack([np.cos(heading), np.sin(heading)])
        lane = tuple(r[c.VAR_LANE_ID] for _, r in rows)
        return (p_ids, flat[:, :2] - direction * (dims[:, :1] / 2.0), direction * flat[:, 3:4], heading, dims, lane,
                np.where([bool(x) for x in lane], flat[:, 4], np.nan), z)

    def _finite(self, flat, ids, is_ego=False) -> np.ndarray | None:
        """None when every row of ``flat`` (x, y, z, angle, ...) has a finite pose, else which to keep: SUMO gave
        a person on a walking area a NaN position for a step (unseen Sao Paulo, striping model); such a road user
        is left out of that step, noted once in SUMO's log (an ego is kept). ``ids`` is read only then."""
        ok = np.isfinite(flat[:, [0, 1, 3]]).all(axis=1) | is_ego
        if ok.all():
            return None
        for vid in itertools.compress(ids, ~ok):
            if vid not in self._no_pose:
                self._no_pose.add(vid)
                self.note(f"sumo-avoid: {vid} has no finite position at {self.time_s:.2f} s; left out of the steps where SUMO gives none")
        return ok

    @staticmethod
    def _signals() -> dict[str, str]:
        state = libsumo.constants.TL_RED_YELLOW_GREEN_STATE
        return {tls: r[state] for tls, r in libsumo.trafficlight.getAllSubscriptionResults().items()}

    @property
    def time_s(self) -> float:
        return libsumo.simulation.getTime()

    def departed(self) -> tuple[str, ...]:
        return tuple(libsumo.simulation.getSubscriptionResults()[libsumo.constants.VAR_DEPARTED_VEHICLES_IDS])

    def note(self, text: str) -> None:
        """A line of the plug-in's in SUMO's message log (the run's sumo.log)."""
        libsumo.simulation.writeMessage(text)

    def waiting(self) -> frozenset[str]:
        """Vehicles whose depart time has come that SUMO could not insert yet."""
        return frozenset(libsumo.simulation.getPendingVehicles())

    def arrived(self) -> frozenset[str]:
        """Vehicles SUMO took out in the last step: at their route's end (nothing else, with no teleporting)."""
        return self._arrived

    def pending(self) -> int:
        """Vehicles loaded but not yet in the network, plus those in it."""
        return libsumo.simulation.getMinExpectedNumber()

    # --- egos ------------------------------------------------------------------------------
    def take_over(self, vid: str, drive: bool = True) -> EgoInfo:
        """Make ``vid`` an ego: recorded as one, and (``drive``) with SUMO's safety checks and lane
        changes off, to be moved by :meth:`apply`; ``drive=False`` leaves it to SUMO's models."""
        if drive:
            libsumo.vehicle.setSpeedMode(vid, EGO_SPEED_MODE)
            libsumo.vehicle.setLaneChangeMode(vid, EGO_LANE_CHANGE_MODE)
        self._users.start()
        self._egos.add(vid)
        self._static_key = None
        self._routes[vid] = tuple(libsumo.vehicle.getRoute(vid))
        return EgoInfo(vid, self._routes[vid], libsumo.vehicle.getLaneIndex(vid), libsumo.vehicle.getWidth(vid),
                       libsumo.vehicle.getLength(vid), self._users.vclass.get(vid) or libsumo.vehicle.getVehicleClass(vid))

    def set_route(self, vid: str, edges) -> bool:
        """Give ego ``vid`` (taken over, on ``edges[0]``) the route ``edges`` in SUMO too; False (and its route
        kept, SUMO's reason in its log) where SUMO refuses it."""
        try:
            libsumo.vehicle.setRoute(vid, list(edges))
        except libsumo.TraCIException as e:
            self.note(f"sumo-avoid: SUMO refused the route round the U-turn(s) for ego '{vid}': {e}")
            return False
        self._routes[vid] = tuple(edges)
        return True

    def follow_route(self, task: EgoTask) -> None:
        """Keep ego ``task.vid`` on its route in SUMO's view while it drives on it (:mod:`.placement`)."""
        self._placement.follow(task, self._routes.get(task.vid, ()))

    def apply(self, ids, centre: np.ndarray, heading: np.ndarray, speed: np.ndarray) -> None:
        """Place each ego exactly (off-lane allowed, also inside junctions) with moveToXY, mapped
        onto its route's lane while it is on it (:class:`~sumo_avoid.sumo.placement.RoutePlacement`)."""
        if len(ids) == 0:
            return
        heading = np.asarray(heading, float)
        half = 0.5 * np.array([self._users.dims[v][0] for v in ids])
        fx = (np.asarray(centre[:, 0], float) + half * np.cos(heading)).tolist()
        fy = (np.asarray(centre[:, 1], float) + half * np.sin(heading)).tolist()
        angle = (90.0 - np.degrees(heading)).tolist()
        move, prev, place = libsumo.vehicle.moveToXY, libsumo.vehicle.setPreviousSpeed, self._placement.place
        for k, (vid, x, y, a, v) in enumerate(zip(ids, fx, fy, angle, np.asarray(speed, float).tolist())):
            edge, lane, mode, route = place(vid, centre[k])
            move(vid, edge, lane, x, y, angle=a, keepRoute=mode)
            if route:
                try:
                    libsumo.vehicle.setRoute(vid, list(route))
                except libsumo.TraCIException:
                    self._placement.lost(vid)
            prev(vid, v)
            self._applied[vid] = v

    def release(self, vid: str) -> None:
        """Take a finished ego out of the simulation. Its subscription goes first: libsumo keeps the
        subscription of a vehicle removed by ``remove`` and the next step fails with "Vehicle 'x' is
        not known" (found with two egos, one at its goal while the other drives on)."""
        self._placement.forget(vid)
        self._applied.pop(vid, None)
        if vid in self._egos:
            self._egos.discard(vid)
            self._static_key = None
        if vid in self._users.dims and vid in libsumo.vehicle.getIDList():
            libsumo.vehicle.unsubscribe(vid)
            libsumo.vehicle.remove(vid)
            self._users.gone([vid], ())

    # --- stepping --------------------------------------------------------------------------
    def step(self) -> list[SumoCollision]:
        try:
            libsumo.simulationStep()
            self._stepped = True
        except (libsumo.TraCIException, libsumo.FatalTraCIError) as e:
            raise SumoStepError(" ".join(str(e).split())) from None
        c, results = libsumo.constants, libsumo.simulation.getSubscriptionResults()
        self._arrived = frozenset(results[c.VAR_ARRIVED_VEHICLES_IDS])
        for vid in self._arrived:
            self._placement.forget(vid)
            self._egos.discard(vid)
            self._applied.pop(vid, None)
            self._static_key = None
        self._users.gone(self._arrived, results[c.VAR_ARRIVED_PERSONS_IDS])
        self._users.add(results[c.VAR_DEPARTED_VEHICLES_IDS], results[c.VAR_DEPARTED_PERSONS_IDS])
        t = self.time_s
        return [SumoCollision(t, k.collider, k.victim, k.type, k.lane) for k in libsumo.simulation.getCollisions()]

    def add_free_vehicles(self, ids, centre: np.ndarray, heading: np.ndarray, speed: float,
                          length_m: float, width_m: float, type_id: str = "flock") -> None:
        """Add vehicles placed at exact centres/headings, off-lane (the arena's flock). They are
        inserted by SUMO at the next step and then reported by :meth:`departed` like route vehicles."""
        if type_id not in libsumo.vehicletype.getIDList():
            libsumo.vehicletype.copy("DEFAULT_VEHTYPE", type_id)
            libsumo.vehicletype.setLength(type_id, float(length_m))
            libsumo.vehicletype.setWidth(type_id, float(width_m))
            libsumo.vehicletype.setMaxSpeed(type_id, FLOCK_MAX_SPEED_MPS)
            libsumo.vehicletype.setMinGap(type_id, 0.0)
        edge = next(e for e in libsumo.edge.getIDList() if not e.startswith(":"))
        route_id = f"__{type_id}_route"
        if route_id not in libsumo.route.getIDList():
            libsumo.route.add(route_id, [edge])
        for k, vid in enumerate(ids):
            libsumo.vehicle.add(vid, route_id, typeID=type_id, depart="now", departSpeed=repr(float(speed)))
            libsumo.vehicle.setSpeedMode(vid, EGO_SPEED_MODE)
            libsumo.vehicle.setLaneChangeMode(vid, EGO_LANE_CHANGE_MODE)
            h = float(heading[k])
            fx = float(centre[k, 0]) + 0.5 * length_m * math.cos(h)
            fy = float(centre[k, 1]) + 0.5 * length_m * math.sin(h)
            libsumo.vehicle.moveToXY(vid, "", -1, fx, fy, angle=90.0 - math.degrees(h), keepRoute=2)

    def add_polygon(self, pid: str, shape: np.ndarray, color=(60, 60, 60, 255)) -> None:
        libsumo.polygon.add(pid, [tuple(map(float, p)) for p in shape], color, fill=True, layer=5)

    def close(self) -> None:
        if libsumo.isLoaded():
            libsumo.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
