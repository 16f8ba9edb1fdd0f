"""Turn radar detections into obstacle footprints a controller can use (no target ids used).

A radar return is one point (the nearest visible point of a target) with a radial speed. A
controller that expects footprints gets, per detection, an assumed car-sized box
(``ASSUMED_LENGTH_M`` x ``ASSUMED_WIDTH_M``) aligned with the traffic's direction (or the sensor's
boresight) with the reflection point on its near side: the middle of its rear face for a car
straight ahead, of its side for a car beside, its corner for a car ahead in the next lane
(:func:`perceived_boxes`), moving with the ego's velocity plus the measured radial speed explained by
motion along the ego's heading (:func:`velocity_estimate`). A box pushed back along the line of
sight instead would put a corner return's car too far into the next lane.
"""
from __future__ import annotations

import numpy as np

from sumo_avoid.core.geometry import footprint_corners, near_any
from sumo_avoid.road.elements import VRU_CLASSES

ASSUMED_LENGTH_M = 4.5
ASSUMED_WIDTH_M = 1.8
#: A person on a sidewalk or walking area walking (at least KERB_STAND_MPS) gets this share of the VRU margin.
KERB_WALKING, KERB_STAND_MPS = 0.5, 0.2
#: A person on a walkway with its centre this far inside the ego's lanes stands on the carriageway
#: (:func:`on_carriageway`), m.
WALKWAY_INTO_LANE_M = 0.5
#: ... its motion is read from the radar only within acos(this) = 60 degrees of the traffic's direction.
KERB_MIN_COS = 0.5
#: A return labelled a person or cyclist is a box of a cyclist's size (a person fits in it), m.
VRU_LENGTH_M, VRU_WIDTH_M = 1.8, 0.8
#: A return this close (m) across (along) the box's axis from the sensor is taken to lie on the
#: middle of the box's rear (side) face; farther, on its corner; in between, in proportion.
FACE_M = 1.0


def velocity_estimate(det, k=None, along=None) -> np.ndarray:
    """(D,2) world velocity of returns ``k`` (all by default), m/s, from their radial speed only.

    The tangential component is unobservable in one return; road traffic moves mostly along the
    ego's heading h, so the target is taken to move along h at the speed s that explains the
    measured radial speed: (s h - v_ego) . u = v_r. Exact for parallel traffic and for stationary
    objects (s = 0). Where h . u < 0.3 (more than ~73 degrees off the heading) the radial-only
    estimate v_ego + v_r u is used instead. ``along`` (rad, scalar or per return) replaces h by a
    better guess of the traffic's direction, e.g. the road's where the ego is: while the ego turns
    or changes lanes its heading is not the traffic's.
    """
    k = np.arange(det.n) if k is None else k
    e = det.ego[k]
    h = det.sensor_heading[e] if along is None else np.broadcast_to(np.asarray(along, float), e.shape)
    hd = np.column_stack([np.cos(h), np.sin(h)])
    a = det.sensor_heading[e] + det.azimuth_rad[k]  # line of sight, world frame
    u = np.column_stack([np.cos(a), np.sin(a)])
    vr = det.radial_speed_mps[k]
    ve = det.sensor_vel[e]
    c = (hd * u).sum(1)
    along = (vr + (ve * u).sum(1)) / np.where(np.abs(c) >= 0.3, c, 1.0)
    return np.where((np.abs(c) >= 0.3)[:, None], along[:, None] * hd, ve + vr[:, None] * u)


def perceived_boxes(det, k=None, along=None, length_m: float = ASSUMED_LENGTH_M, width_m: float = ASSUMED_WIDTH_M):
    """Returns ``k`` (all by default) as assumed boxes: (pos (M,2), heading (M,), length (M,),
    width (M,), vel (M,2)); ``det.ego[k]`` says whose. Boxes and motion are aligned with ``along``
    (rad, the traffic's direction; a scalar or one per return) if given, else with the sensor's boresight."""
    k = np.arange(det.n) if k is None else np.asarray(k, int)
    M = len(k)
    if M == 0:
        z = np.zeros(0)
        return np.zeros((0, 2)), z, z, z, np.zeros((0, 2))
    e = det.ego[k]
    h = det.sensor_heading[e] if along is None else np.broadcast_to(np.asarray(along, float), (M,)).copy()  # box axis
    a = det.sensor_heading[e] + det.azimuth_rad[k]  # line of sight, world frame
    u = np.column_stack([np.cos(a), np.sin(a)])
    hd = np.column_stack([np.cos(h), np.sin(h)])
    nd = np.column_stack([-hd[:, 1], hd[:, 0]])
    point = det.sensor_pos[e] + det.range_m[k][:, None] * u
    # where the return lies on the box: (a, b) = the point from the sensor along / across the box's
    # axes; a box's nearest point is the middle of its face towards the sensor (b = 0: the box
    # straight ahead; a = 0: beside) or its corner. The centre is half a length on along, half a
    # width across, each scaled down over the first FACE_M from the face's foot
    a = det.range_m[k] * (u * hd).sum(1)
    b = det.range_m[k] * (u * nd).sum(1)
    pos = (point + (0.5 * length_m * np.sign(a) * np.minimum(np.abs(a) / FACE_M, 1.0))[:, None] * hd
           + (0.5 * width_m * np.sign(b) * np.minimum(np.abs(b) / FACE_M, 1.0))[:, None] * nd)
    vel = velocity_estimate(det, k, along)
    return pos, h, np.full(M, length_m), np.full(M, width_m), vel


def perceived_obstacles(det, vid: str, length_m: float = ASSUMED_LENGTH_M, width_m: float = ASSUMED_WIDTH_M,
                        along: float | None = None):
    """Obstacles seen by ego ``vid`` (:func:`perceived_boxes` of its returns)."""
    return perceived_boxes(det, det.of(vid), along, length_m, width_m)


def obstacle_vehicles(obs, row: int, q, radius_m: float, walkways=frozenset()):
    """Other road users for the ego at snapshot ``row`` as (pos, heading, length, width, vel, vru, kerb):
    from the radar when ``obs.detections`` is set (moving along ``obs.route_heading`` of that ego
    if given, see :func:`perceived_boxes`), else ground truth within ``radius_m`` of q. ``vru``
    (float, :func:`_weight`) is the share of the controller's VRU margin each one gets: 1 for a person
    or cyclist (:data:`~sumo_avoid.road.elements.VRU_CLASSES`; from ground truth, or the radar's label
    of the return) on the carriageway; a person on one of the ``walkways`` (lane ids: sidewalks, walking
    areas) is off it: half walking, none standing (a car passes the people waiting at a corner at their
    size; SUMO puts them at the kerb's edge, inside a tight turn's margin); a radar return is placed on
    the map by the sensor (``Detections.walkway``) and judged the same way. ``kerb`` (bool) marks the people on
    a walkway (behind the kerb, off the carriageway). Road users on another level
    than the ego (:mod:`sumo_avoid.core.levels`: a car on a bridge over it) are left out."""
    snap = obs.snapshot
    if obs.detections is not None:  # one scan per radar mount (front, rear)
        route = obs.route_heading
        along = None if route is None else float(route[obs.index(snap.ids[row])])
        parts = [_obstacles_of(d, snap.ids[row], along) for d in obs.detections]
        return tuple(np.concatenate(x) for x in zip(*parts)) if len(parts) > 1 else parts[0]
    d = np.hypot(*(snap.pos - np.asarray(q, float)).T)
    o = np.flatnonzero((d < radius_m) & (np.arange(snap.n) != row))
    if snap.levels:  # a road user on another level (over a bridge, in a tunnel) is no obstacle (core.levels)
        o = o[snap.same_level(row, o)]
    vru = snap.is_person[o] | np.array([snap.vclass[i] in VRU_CLASSES for i in o], bool).reshape(len(o))
    kerb = np.array([snap.is_person[i] and snap.lane[i] in walkways for i in o], bool).reshape(len(o)) \
        if walkways and vru.any() else np.zeros(len(o), bool)
    return snap.pos[o], snap.heading[o], snap.length[o], snap.width[o], snap.vel[o], _weight(vru, kerb, snap.vel[o]), kerb


def _weight(vru, kerb, vel) -> np.ndarray:
    """(N,) share of the VRU margin each road user gets: 1 a person or cyclist on the carriageway; on a
    walkway :data:`KERB_WALKING` walking (it may step off), 0 standing (it waits: the car passes it at its
    size); 0 anything else."""
    walking = np.hypot(vel[:, 0], vel[:, 1]) >= KERB_STAND_MPS if len(vel) else np.zeros(0, bool)
    return np.where(vru, np.where(kerb, np.where(walking, KERB_WALKING, 0.0), 1.0), 0.0)


def on_carriageway(share, kerb, d, lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """(share, kerb), (N,) each: a person on a walkway whose centre (``d`` across the road) lies
    :data:`WALKWAY_INTO_LANE_M` or more inside the ego's lanes (``lo``..``hi`` at its place; a junction's walking
    area laid over an internal lane) stands on the carriageway: the full margin (share 1), not behind the kerb.
    SUMO puts people waiting at a corner up to 0.2 m into the lane (their centres at the lane's edge), and a radar
    places them within a few tenths of a metre: they stay at the kerb."""
    d = np.asarray(d, float)
    inside = (d > np.asarray(lo) + WALKWAY_INTO_LANE_M) & (d < np.asarray(hi) - WALKWAY_INTO_LANE_M)
    deep = np.asarray(kerb, bool) & inside
    return np.where(deep, 1.0, np.asarray(share, float)), np.asarray(kerb, bool) & ~deep


def towards_path(share, closing_mps) -> np.ndarray:
    """(N,) the VRU margin's share (:func:`_weight`) once the controller knows each road user's speed
    towards the ego's path across the road (``closing_mps``): a person on a walkway keeps its share only
    while it walks towards the path faster than :data:`KERB_STAND_MPS`; walking along the kerb it is passed
    at its size, like one standing there."""
    share = np.asarray(share, float)
    kerb = (share > 0.0) & (share < 1.0)
    return np.where(kerb & (np.asarray(closing_mps, float) <= KERB_STAND_MPS), 0.0, share)


def _lane_along(det, k, small, along):
    """Per return ``k`` of a car-sized road user: the direction of the map's normal lane it lies in
    (``Road.lane_heading``), else ``along`` (the traffic's direction at the ego; the boresight if None). Inside a turn the
    traffic's direction at the ego is no one else's: a car crossing in front of an ego turning right at
    Bologna's junction 50 became a box across the ego's strip, and the ego stood in the turn with its nose in
    the crossing cars' path (bologna_pepoli, radar, seed 2: 8 contacts). A labelled person or cyclist keeps
    ``along`` (its box is small; a person's way across the road is no lane's)."""
    lane = None if det.lane_heading is None else det.lane_heading[k]
    if lane is None or not len(k):
        return along
    base = det.sensor_heading[det.ego[k]] if along is None else np.full(len(k), float(along))
    return np.where(np.isfinite(lane) & ~small, lane, base)


def _obstacles_of(det, vid: str, along):
    """One scan's returns of ego ``vid`` as boxes (a car's; a labelled person's or cyclist's
    :data:`VRU_LENGTH_M` x :data:`VRU_WIDTH_M`), their VRU marks (not on a walkway) and walkway marks."""
    k = det.of(vid)
    small = det.vru_mask()[k]
    pos, hd, ln, wd, vel = perceived_boxes(det, k, _lane_along(det, k, small, along))
    kerb = det.walkway_mask()[k]
    if small.any():
        j = np.flatnonzero(small)
        pos[j], hd[j], ln[j], wd[j], vel[j] = perceived_boxes(det, k[j], along, VRU_LENGTH_M, VRU_WIDTH_M)
        w = np.flatnonzero(small & kerb)
        if len(w):  # a person at the kerb seen far off the traffic's direction: its motion is not known
            vel[w[~observable(det, k[w], along)]] = 0.0
    return pos, hd, ln, wd, vel, _weight(small, kerb, vel), small & kerb


def observable(det, k, along=None, min_cos: float = KERB_MIN_COS) -> np.ndarray:
    """(D,) bool: is the motion along the traffic's direction (``along``, else the boresight) of returns
    ``k`` observable from their radial speed -- the line of sight within acos(``min_cos``) of it?
    :func:`velocity_estimate` divides the radial speed by that cosine; for a person at the kerb beside
    the ego (up to 73 degrees off) it turned a standing person's noise into 3.65 m/s walking towards the
    ego's path (bologna_bus_lane, radar, seed 3: the margin it kept pushed the ego towards a bus in the
    oncoming lane). Taking its velocity from the line of sight instead misreads people walking along the
    sidewalk ahead as walking towards the road (signal_crossing_right, radar, seed 5); beyond the bound
    a person at the kerb is taken to stand (it keeps no margin; the crossing rule watches the crossings)."""
    e = det.ego[k]
    h = det.sensor_heading[e] if along is None else np.broadcast_to(np.asarray(along, float), e.shape)
    a = det.sensor_heading[e] + det.azimuth_rad[k]
    return np.abs(np.cos(a - h)) >= min_cos


def radar_obstacles(obs, known_pos, gate_m: float):
    """All egos' returns in ``obs.detections`` as assumed boxes, minus those whose box centre lies
    within ``gate_m`` of a ``known_pos`` (vehicles known otherwise, e.g. flock members over V2V;
    no target ids used). Returns (corners (B,4,2), velocities (B,2), owner (B,) index into
    ``obs.ego_ids``)."""
    scans = obs.detections
    row_of = {v: k for k, v in enumerate(obs.ego_ids)}
    parts = [(perceived_boxes(d), np.array([row_of[d.ego_ids[e]] for e in d.ego], dtype=int)) for d in scans]
    pos, hd, ln, wd, vel = (np.concatenate([b[i] for b, _ in parts]) for i in range(5))
    owner = np.concatenate([o for _, o in parts])
    if len(pos) and len(known_pos):
        keep = ~near_any(pos, known_pos, gate_m)
        pos, hd, ln, wd, vel, owner = pos[keep], hd[keep], ln[keep], wd[keep], vel[keep], owner[keep]
    return footprint_corners(pos, hd, ln, wd), vel, owner
