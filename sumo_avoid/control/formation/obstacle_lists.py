"""What each member of the ``formation`` controller knows of its surroundings (docs/formation.md,
"Sensing and V2V"): the static obstacles, other vehicles and radar returns as one list of convex
polygons with, per member, which it feels in its field and which in its safety shield, and the hulls
over gaps no member passes (:func:`.field.bridges`)."""
from __future__ import annotations

import numpy as np

from sumo_avoid.control.formation import field as ff
from sumo_avoid.core.geometry import footprint_corners, pad_polygons
from sumo_avoid.core.types import Observation
from sumo_avoid.sensing.perception import radar_obstacles


class ObstacleLists:
    """The static obstacles a formation knows (``set_static``: in the plane, or mapped into the
    leader's route frame on a road) and, each step, the lists of everything its members know
    (:meth:`lists`); owned by :class:`~sumo_avoid.control.formation.formation.FormationController`."""

    def __init__(self, params, static_polys):
        self.p = params  # FormationParams
        self.set_static(static_polys)

    def set_static(self, polys) -> None:
        self.static = tuple(polys)
        self._static_polys = pad_polygons(self.static) if self.static else np.zeros((0, 4, 2))
        self._static_c = np.array([o.mean(axis=0) for o in self.static]).reshape(-1, 2)
        self._static_r = np.array([np.hypot(*(o - o.mean(axis=0)).T).max() for o in self.static])
        self._bridges = None  # (hulls, pairs) of the gaps no member's disc passes: ff.bridges, at the first step

    def lists(self, obs: Observation, lead_row, member_pos, members, shared: bool):
        """(polys (O,K,2), mask (E,O) which ego's field feels which, leader's (O,) bool, static (O,) bool,
        velocities (O,2), shield mask (E,O)); ``members``: the formation's ids (known over V2V, no
        obstacles); ``shared``: every member knows everything (ground truth in the leader's route
        frame on a road). The leader's list is shared with every member (V2V); what a
        follower senses itself (its radar; truth: within ``sense_radius_m`` of it) it adds for itself (a
        follower far behind the leader is near obstacles the leader has passed). The hulls over gaps
        too narrow to
        pass (:meth:`_shut_gaps`) go to the field alone."""
        snap, E = obs.snapshot, len(obs.ego_ids)
        parts, know, vel, shut = [], [], [], []  # know (E, n): which member knows which; shut: a hull
        if obs.detections is None:  # around every member
            where, r = snap.pos[obs.ego_rows], self.p.sense_radius_m
            lead = lead_row is not None and not shared
            lk = int(np.flatnonzero(np.asarray(obs.ego_rows) == lead_row)[0]) if lead else None
            if len(self.static):
                k = np.hypot(*(self._static_c[None] - where[:, None]).transpose(2, 0, 1)) - self._static_r <= r
                k = k | k[lk] if lead else k.any(axis=0)[None].repeat(E, axis=0)
                near = k.any(axis=0)
                parts.append(self._static_polys[near])
                know.append(k[:, near])
                vel.append(np.full((int(near.sum()), 2), np.nan))  # NaN: a static obstacle
                hulls, hk = self._shut_gaps(k, snap.length[obs.ego_rows], snap.width[obs.ego_rows])
                parts.append(hulls)
                know.append(hk)
                vel.append(np.full((len(hulls), 2), np.nan))
                shut.append(np.r_[np.zeros(int(near.sum()), bool), np.ones(len(hulls), bool)])
            members = set(members)
            o = np.array([k for k, v in enumerate(snap.ids) if v not in members], int)
            if len(o):
                k = np.hypot(*(snap.pos[o][None] - where[:, None]).transpose(2, 0, 1)) <= r
                if snap.levels:  # on another level (a bridge over the member): no obstacle (core.levels)
                    k &= np.array([snap.same_level(int(r), o) for r in obs.ego_rows]).reshape(k.shape)
                o, k = o[k.any(axis=0)], k[:, k.any(axis=0)]
                ahead = self.p.predict_s * snap.vel[o]  # each as the box it sweeps within predict_s
                parts.append(footprint_corners(snap.pos[o] + 0.5 * ahead, snap.heading[o],
                                               snap.length[o] + np.hypot(*ahead.T), snap.width[o]))
                know.append(k | k[lk] if lead else np.ones_like(k))
                vel.append(snap.vel[o] * (self.p.predict_s <= 0))  # a swept box stands still
                shut.append(np.zeros(len(o), bool))
            lead_k = lk
        else:
            corners, rv, who = radar_obstacles(obs, member_pos, self.p.v2v_gate_m)
            lead_k = obs.ego_ids.index(snap.ids[lead_row]) if lead_row is not None else None
            parts.append(corners)
            vel.append(rv)
            mine = np.asarray(who)[None, :] == np.arange(E)[:, None]
            know.append(mine | (mine[lead_k] if lead_k is not None else False))
            shut.append(np.zeros(len(who), bool))
        keep = [i for i, x in enumerate(parts) if len(x)]
        if not keep:
            e = np.zeros((E, 0), bool)
            return np.zeros((0, 4, 2)), e, np.zeros(0, bool), np.zeros(0, bool), np.zeros((0, 2)), e
        polys = pad_polygons([pg for i in keep for pg in parts[i]])
        know = np.concatenate([know[i] for i in keep], axis=1)
        vel = np.concatenate([vel[i] for i in keep]).reshape(-1, 2)
        shut = np.concatenate(shut) if shut else np.zeros(len(polys), bool)
        static = np.isnan(vel[:, 0])
        lead_knows = know[lead_k] & ~shut if lead_k is not None else np.zeros(len(polys), bool)
        return polys, know, lead_knows, static, np.where(static[:, None], 0.0, vel), know & ~shut[None]

    def _shut_gaps(self, know, length, width):
        """Hulls closing the gaps between the static obstacles that no member's disc passes
        (:func:`.field.bridges`; the field goes round them, the shield still sees only the
        obstacles): ((B, H, 2), (E, B) which member knows both obstacles, from ``know`` (E, O))."""
        if self._bridges is None:
            r = float(0.5 * np.hypot(length, width).max())
            self._bridges = ff.bridges(self._static_polys, 2.0 * (r + self.p.shield_margin_m))
        hulls, pairs = self._bridges
        hk = know[:, pairs[:, 0]] & know[:, pairs[:, 1]]
        used = hk.any(axis=0)
        return hulls[used], hk[:, used]
