"""Random static obstacles drawn from the scenario seed (the ``[random_obstacles]`` table).

The seed-003 experiment places its obstacles at random on the way from the start to the goal, a
new layout per run. Here the layout is a pure function of the scenario (the table) and its seed
(``numpy.random.default_rng([seed, STREAM])``): the loader appends the drawn polygons to the
scenario's ``[[obstacles]]`` (ids ``PREFIX0``, ``PREFIX1``, ...), so SUMO, the sensors, the
controllers, the metrics and the plots see them like any other obstacle, and the same scenario and
seed always give the same layout.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sumo_avoid.core.config import FieldError, field_doc

STREAM = 13  # the layout's own random stream: [seed, 13]


@dataclass(frozen=True)
class RandomObstaclesConfig:
    count: int = field_doc(40, doc="number of obstacles")
    region: tuple[float, ...] = field_doc((0.0, 0.0, 100.0, 100.0), signed=True,
                                          doc="[x0, y0, x1, y1]: obstacle centres are drawn uniformly in this box, m")
    radius_min_m: float = field_doc(1.0, positive=True, doc="smallest obstacle radius (circumscribed), m")
    radius_max_m: float = field_doc(2.5, positive=True, doc="largest obstacle radius, m")
    sides: int = field_doc(8, doc="each obstacle is a regular polygon with this many sides, randomly turned")
    keep_clear: tuple[tuple[float, ...], ...] = field_doc((), signed=True,
                                                          doc="[[x, y], ...] points no obstacle may come near "
                                                              "(starts, goals)")
    clear_radius_m: float = field_doc(6.0, doc="obstacle edges keep this far from every keep_clear point, m")
    min_gap_m: float = field_doc(2.0, doc="obstacles keep at least this far apart (circumscribed circles), m")
    id_prefix: str = field_doc("rob", doc="obstacle ids are PREFIX0, PREFIX1, ...")

    def __post_init__(self):
        if len(self.region) != 4 or self.region[2] <= self.region[0] or self.region[3] <= self.region[1]:
            raise FieldError("region", "[x0, y0, x1, y1] with x1 > x0 and y1 > y0", list(self.region))
        if self.radius_max_m < self.radius_min_m:
            raise FieldError("radius_max_m", f">= radius_min_m ({self.radius_min_m})", self.radius_max_m)
        if self.sides < 3:
            raise FieldError("sides", "an integer >= 3", self.sides)
        if self.count < 0:
            raise FieldError("count", "an integer >= 0", self.count)
        if any(len(p) != 2 for p in self.keep_clear):
            raise FieldError("keep_clear", "a list of [x, y] points", [list(p) for p in self.keep_clear])


def draw(cfg: RandomObstaclesConfig, seed: int, max_tries: int = 100_000) -> list[np.ndarray]:
    """``cfg.count`` regular polygons ((sides, 2) CCW vertices, m), by sequential rejection sampling
    (deterministic for a seed). Raises ValueError if they do not fit in ``max_tries`` draws."""
    rng = np.random.default_rng([seed, STREAM])
    x0, y0, x1, y1 = cfg.region
    # disks of radius r_min + gap/2 cannot cover more than pi / sqrt(12) (hexagonal packing) of the
    # region grown by that radius: past that no draw can succeed
    r = cfg.radius_min_m + 0.5 * cfg.min_gap_m
    if cfg.count * np.pi * r**2 > np.pi / np.sqrt(12.0) * (x1 - x0 + 2 * r) * (y1 - y0 + 2 * r):
        raise ValueError(f"{cfg.count} obstacles of radius >= {cfg.radius_min_m} m, {cfg.min_gap_m} m apart, "
                         "cannot fit the region")
    clear = np.asarray(cfg.keep_clear, float).reshape(-1, 2)
    centres, radii, out = [], [], []
    tries = 0
    while len(out) < cfg.count:
        tries += 1
        if tries > max_tries:
            raise ValueError(f"could not place {cfg.count} obstacles (placed {len(out)})")
        c = rng.uniform((x0, y0), (x1, y1))
        r = rng.uniform(cfg.radius_min_m, cfg.radius_max_m)
        turn = rng.uniform(0.0, 2.0 * np.pi / cfg.sides)
        if len(clear) and np.hypot(*(clear - c).T).min() < r + cfg.clear_radius_m:
            continue
        if centres and (np.hypot(*(np.array(centres) - c).T) - np.array(radii)).min() < r + cfg.min_gap_m:
            continue
        a = turn + 2.0 * np.pi * np.arange(cfg.sides) / cfg.sides
        out.append(c + r * np.column_stack([np.cos(a), np.sin(a)]))
        centres.append(c)
        radii.append(r)
    return out
