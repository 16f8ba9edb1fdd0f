"""Which of SUMO's road users the plug-in is subscribed to, and their static sizes and classes (a part of
:class:`~sumo_avoid.sumo.sim.SumoSim`, which hands it libsumo's vehicle and person domains: this module imports no
libsumo itself).

Every vehicle and person is subscribed as it departs (the variables ``SumoSim`` names: position, angle, speed, lane,
lane position; a person also whether it rides) and forgotten when it arrives. Until the first ego is taken over a run
may ``defer``: SUMO computes every subscribed road user's variables in each of its steps, and before any ego
nothing read is used when the recording keeps only the road users near egos (a district's warm-up, Bologna's first
300 s: ``benchmarks/warmup.py``). Deferred, the departures and arrivals are only noted, in order, and
:meth:`RoadUsers.start` subscribes those still in the net when the first ego is taken over (the subscription
results are keyed by id: the rows come out as they would have).
"""
from __future__ import annotations


class RoadUsers:
    def __init__(self, vehicles, persons, vehicle_vars, person_vars):
        """``vehicles``, ``persons``: libsumo's ``vehicle`` and ``person`` domains; ``*_vars``: the variables to subscribe."""
        self._domains = (vehicles, persons)
        self._vars = (list(vehicle_vars), list(person_vars))
        self.dims: dict[str, tuple[float, float]] = {}  # vehicle id -> (length, width), static
        self.vclass: dict[str, str] = {}  # vehicle id -> SUMO vehicle class, static
        self.persons: dict[str, tuple[float, float]] = {}  # person id -> (length, width), static
        self.defer = False  # note departures only, until start()
        self._later: tuple[dict, dict] = ({}, {})  # vehicles, persons departed meanwhile (ordered ids)

    def add(self, vehicles, persons) -> None:
        """Subscribe to departed ``vehicles`` and ``persons`` (ids), or note them while deferring."""
        if self.defer:
            self._later[0].update(dict.fromkeys(vehicles))
            self._later[1].update(dict.fromkeys(persons))
            return
        cars, people = self._domains
        for vid in vehicles:
            if vid not in self.dims:
                cars.subscribe(vid, self._vars[0])
                self.dims[vid] = (cars.getLength(vid), cars.getWidth(vid))
                self.vclass[vid] = cars.getVehicleClass(vid)
        for pid in persons:
            if pid not in self.persons:
                people.subscribe(pid, self._vars[1])
                self.persons[pid] = (people.getLength(pid), people.getWidth(pid))

    def gone(self, vehicles, persons) -> None:
        """Forget arrived ``vehicles`` and ``persons`` (ids)."""
        for vid in vehicles:
            self.dims.pop(vid, None)
            self.vclass.pop(vid, None)
            self._later[0].pop(vid, None)
        for pid in persons:
            self.persons.pop(pid, None)
            self._later[1].pop(pid, None)

    def start(self) -> None:
        """Stop deferring: subscribe to the road users noted meanwhile that are still in the net."""
        if not self.defer:
            return
        self.defer = False
        cars, people = self._later
        live, here = (set(d.getIDList()) for d in self._domains)
        self._later = ({}, {})
        self.add([v for v in cars if v in live], [p for p in people if p in here])
