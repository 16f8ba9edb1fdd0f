"""The numpy formulation of the radar's occlusion step that sumo_avoid/sensors/occlusion.py (numba)
replaced, kept as an independent reference: tests/sensing/test_radar.py checks that the kernel gives this
one's detections, their values within 1e-12 relative (two implementations: not bit for bit), on random
scenes and on a dense-traffic scene. Vectorised over all
egos and targets: candidates padded into (E, T) blocks, angular intervals, sectors owned by the
target their middle ray hits first, nearest visible point at owned sector ends or special angles.
Also kept: the numpy footprints (``targets_reference``) and the k-d tree candidate stage
(``_candidates``) that the compiled ``occlusion.boxes`` and ``occlusion.candidates`` replaced.
"""
import itertools
import math

import numpy as np

from sumo_avoid.core.geometry import footprint_corners
from sumo_avoid.core.geometry import wrap_angle as _wrap


def _candidates(spos, fwd, centre, radius, rows, max_range_m: float, half_rad: float):
    """(ego, target) pairs, sorted by ego then target, whose circumscribed disc meets the range
    disc and the FOV wedge (|lateral| cos(half) - forward sin(half) <= radius: the disc reaches
    the wedge's side); never the ego itself. A k-d tree over the target centres gives each ego its
    neighbours within range (+ the largest radius); the exact tests then run on those pairs only."""
    from scipy.spatial import cKDTree

    E = len(spos)
    if E == 0 or len(centre) == 0:
        return np.zeros(0, int), np.zeros(0, int)
    reach = (max_range_m + float(radius.max())) * (1 + 1e-9) + 1e-6  # a superset of the exact test
    near = cKDTree(centre).query_ball_point(spos, reach, return_sorted=True)
    e = np.repeat(np.arange(E), [len(x) for x in near])
    n = np.fromiter(itertools.chain.from_iterable(near), dtype=int, count=len(e))
    dx, dy = centre[n, 0] - spos[e, 0], centre[n, 1] - spos[e, 1]
    fx, fy = fwd[e, 0], fwd[e, 1]
    ahead, side = dx * fx + dy * fy, np.abs(dy * fx - dx * fy)
    r = radius[n]
    keep = ((dx * dx + dy * dy <= (max_range_m + r) ** 2) & (ahead >= -r)
            & (side * math.cos(half_rad) - ahead * math.sin(half_rad) <= r) & (n != rows[e]))
    return e[keep], n[keep]


def targets_reference(snap, obstacles=()):
    """Everything a radar can see: vehicles' footprints (4 corners) and static polygons, padded to
    K vertices by repeating the last one. Returns polys (N, K, 2), velocities (N, 2), ids (N,),
    centres (N, 2) and circumscribed radii (N,)."""
    corners = footprint_corners(snap.pos, snap.heading, snap.length, snap.width)
    polys = [np.asarray(o, float).reshape(-1, 2) for o in obstacles]
    K = max([4] + [len(o) for o in polys])
    allc = [np.concatenate([corners, np.repeat(corners[:, -1:], K - 4, axis=1)], axis=1)]
    allc += [np.concatenate([o, np.repeat(o[-1:], K - len(o), axis=0)])[None] for o in polys]
    allc = np.concatenate(allc) if polys else allc[0]
    ids = tuple(snap.ids) + tuple(f"obstacle{i}" for i in range(len(polys)))
    vel = np.concatenate([snap.vel, np.zeros((len(polys), 2))]) if polys else snap.vel
    centre = allc.mean(axis=1)
    radius = np.sqrt(((allc - centre[:, None]) ** 2).sum(-1)).max(axis=1)
    return allc, vel, ids, centre, radius



def _pad_candidates(mask: np.ndarray):
    """(E, N) bool -> (E, T) target indices and (E, T) validity, T = max candidates per ego."""
    e, n = np.nonzero(mask)  # row-major: each ego's candidates in increasing target order
    return _pad_pairs(e, n, mask.shape[0])


def _pad_pairs(e: np.ndarray, n: np.ndarray, E: int):
    """(ego, target) pairs sorted by ego -> (E, T) target indices and (E, T) validity."""
    counts = np.bincount(e, minlength=E)
    T = int(counts.max()) if E else 0
    idx = np.zeros((E, T), dtype=int)
    valid = np.arange(T)[None, :] < counts[:, None]
    idx[valid] = n
    return idx, valid


def ray_depth(rel: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Distance along rays from the origin to the boundary of convex polygons.

    rel (..., K, 2) polygon vertices relative to the ray origin, angles (...) ray directions (rad,
    world frame), broadcast together. Returns (...): distance to the first boundary crossing, inf
    if the ray misses. E.g. rel (E,T,1,K,2) with angles (E,1,R) gives (E,T,R).
    """
    a = rel
    b = np.roll(rel, -1, axis=-2)
    dx, dy = np.cos(angles)[..., None], np.sin(angles)[..., None]
    abx, aby = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    denom = dx * aby - dy * abx
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (a[..., 0] * aby - a[..., 1] * abx) / denom
        u = (a[..., 0] * dy - a[..., 1] * dx) / denom
    hit = (np.abs(denom) > 1e-12) & (u >= -1e-9) & (u <= 1 + 1e-9) & (s >= 0)
    return np.where(hit, s, np.inf).min(axis=-1)


def _shadowed(rel: np.ndarray, lo: np.ndarray, hi: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """(E,T) True where a target lies wholly in the shadow of ONE other, nearer target.

    j is hidden by i when i's angular interval covers j's (both clipped to the field of view) and
    i's farthest vertex is nearer than j's nearest boundary point: every ray towards j then hits
    the convex i first. A cheap, exact-but-incomplete pre-filter (targets hidden only by several
    others together are left to the sector test); in dense traffic it removes most candidates.
    """
    far = np.sqrt((rel**2).sum(-1)).max(axis=2)  # (E,T)
    ab = np.roll(rel, -1, axis=2) - rel
    L2 = (ab**2).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        tf = np.clip(np.where(L2 > 1e-12, -(rel * ab).sum(-1) / L2, 0.0), 0.0, 1.0)
    near = np.sqrt(((rel + tf[..., None] * ab) ** 2).sum(-1)).min(axis=2)  # (E,T)
    cover = (ok[:, :, None] & (lo[:, :, None] <= lo[:, None, :]) & (hi[:, None, :] <= hi[:, :, None])
             & (far[:, :, None] < near[:, None, :]))  # (E, i, j): i shadows j
    return ok & cover.any(axis=1)


def _visible(p, spos, hd, svel, poly, tvel, valid, idx, ids) -> dict:
    half = math.radians(p.fov_deg) / 2
    E = len(spos)
    rel = poly - spos[:, None, None, :]  # (E,T,K,2)
    az = _wrap(np.arctan2(rel[..., 1], rel[..., 0]) - hd[:, None, None])  # (E,T,K)
    lo, hi = az.min(axis=2), az.max(axis=2)
    ok = valid & (hi - lo < np.pi) & (np.maximum(lo, -half) < np.minimum(hi, half))
    ok &= ~_shadowed(rel, np.maximum(lo, -half), np.minimum(hi, half), ok)
    # keep only candidates inside the field of view and not in one nearer target's shadow
    # (re-pad: T shrinks to the largest count)
    sel, ok = _pad_candidates(ok)
    take = lambda a: np.take_along_axis(a, sel.reshape(sel.shape + (1,) * (a.ndim - 2)), axis=1)  # noqa: E731
    rel, az, lo, hi, tvel, idx = take(rel), take(az), take(lo), take(hi), take(tvel), take(idx)
    T = rel.shape[1]
    if T == 0:
        return dict(ego=np.zeros(0, int), range_m=np.zeros(0), azimuth_rad=np.zeros(0),
                    radial_speed_mps=np.zeros(0), target=())
    # occlusion: the covering set only changes at interval ends, so the FOV is cut at every
    # usable candidate's [lo, hi]; the target hit first by a sector's middle ray owns the sector
    # (disjoint convex footprints keep their depth order across a sector)
    cuts = np.where(ok[:, :, None], np.clip(np.stack([lo, hi], axis=2), -half, half), half)
    cuts = np.sort(np.concatenate([cuts.reshape(E, -1), np.full((E, 1), -half)], axis=1), axis=1)
    a0, a1 = cuts[:, :-1], cuts[:, 1:]  # (E,S)
    width = a1 - a0
    dmid = ray_depth(rel[:, :, None], (0.5 * (a0 + a1) + hd[:, None])[:, None, :])  # (E,T,S)
    dmid = np.where(ok[:, :, None], dmid, np.inf)
    owner = dmid.argmin(axis=1)  # (E,S)
    has = np.isfinite(np.take_along_axis(dmid, owner[:, None], axis=1)[:, 0]) & (width > 1e-9)
    own = (owner[:, None, :] == np.arange(T)[None, :, None]) & has[:, None, :]  # (E,T,S)
    seen = ok & own.any(axis=2)
    # nearest visible point of each seen target: its distance along a straight piece of its
    # boundary is monotone between its vertices and the feet of the perpendiculars from the
    # sensor, so the minimum is at an end of an owned sector or at one of those special angles
    ab = np.roll(rel, -1, axis=2) - rel
    L2 = (ab**2).sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        tf = np.clip(np.where(L2 > 1e-12, -(rel * ab).sum(-1) / L2, 0.0), 0.0, 1.0)
    foot = rel + tf[..., None] * ab
    special = np.concatenate([az, _wrap(np.arctan2(foot[..., 1], foot[..., 0]) - hd[:, None, None])], axis=2)
    inside = ((own[:, :, None, :] & (a0[:, None, None, :] <= special[..., None])
               & (special[..., None] <= a1[:, None, None, :])).any(axis=3))  # (E,T,2K)
    d_sp = np.where(inside, ray_depth(rel[:, :, None], special + hd[:, None, None]), np.inf)
    eps = np.minimum(1e-7, 0.25 * width)
    ends = np.stack([a0 + eps, a1 - eps], axis=-1)  # (E,S,2), nudged onto the sector
    opoly = np.take_along_axis(rel, owner[:, :, None, None], axis=1)  # (E,S,K,2)
    dend = ray_depth(opoly[:, :, None], ends + hd[:, None, None])  # (E,S,2)
    d_end = np.where(own[..., None], dend[:, None], np.inf).reshape(E, T, -1)  # (E,T,2S)
    a_end = np.broadcast_to(np.stack([a0, a1], axis=-1)[:, None], (E, T) + a0.shape[1:] + (2,)).reshape(E, T, -1)
    d_all = np.concatenate([d_end, d_sp], axis=2)
    a_all = np.concatenate([a_end, special], axis=2)
    best = d_all.argmin(axis=2)
    rng_vis = np.take_along_axis(d_all, best[..., None], axis=2)[..., 0]
    az_vis = np.take_along_axis(a_all, best[..., None], axis=2)[..., 0]
    seen &= rng_vis <= p.max_range_m
    e, t = np.nonzero(seen)
    az_w = hd[e] + az_vis[e, t]
    u = np.column_stack([np.cos(az_w), np.sin(az_w)])
    vr = np.einsum("ij,ij->i", tvel[e, t] - svel[e], u)
    return dict(ego=e, range_m=rng_vis[e, t], azimuth_rad=az_vis[e, t], radial_speed_mps=vr,
                target=tuple(ids[i] for i in idx[e, t]))


def visible_reference(radar, snap, ego_ids, obstacles=()) -> dict:
    """What the numpy formulation detects (before imperfections) for ``radar``'s mount."""
    rows = np.array([snap.index[v] for v in ego_ids], dtype=int)
    spos, hd, fwd = radar.pose(snap, rows)
    polys, vel, ids, centre, radius = targets_reference(snap, obstacles)
    e, n = _candidates(spos, fwd, centre, radius, rows, radar.p.max_range_m, math.radians(radar.p.fov_deg) / 2)
    idx, valid = _pad_pairs(e, n, len(rows))
    if not idx.shape[1]:
        return dict(ego=np.zeros(0, int), range_m=np.zeros(0), azimuth_rad=np.zeros(0),
                    radial_speed_mps=np.zeros(0), target=())
    return _visible(radar.p, spos, hd, snap.vel[rows], polys[idx], vel[idx], valid, idx, ids)
