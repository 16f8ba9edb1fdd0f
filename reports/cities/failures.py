"""What the recording shows for every run of a city-suite ledger that fails an acceptance count: its contacts (ours
and SUMO's with the ego: time, the other road user and its class, the ego's lane, speed and angle to its lane's
direction) and, for a run without its goal, where the ego stood still at the end and since when, with the nearest
road users ahead of it. The causes in reports/cities/README.md are read from this, the run's viewer
(`sumo-avoid report RUN_DIR`) and its trajectories.csv.

Usage: python reports/cities/failures.py LEDGER.sqlite [CONTROLLER]   (default apf_sa)
"""
import json
import math
import pathlib
import sys

import numpy as np
import pandas as pd

from sumo_avoid.studies import ledger

COUNTS = ("collisions", "sumo_ego_collisions", "vru_collisions", "red_light_violations", "yield_violations",
          "stop_sign_violations", "crossing_violations")


def _fails(r) -> list[str]:
    out = [f"{c} {int(r[c])}" for c in COUNTS if r[c] == r[c] and r[c] > 0]
    out += [f"{c} {r[c]:.1f}" for c in ("off_road_m", "forbidden_lane_m", "wrong_way_m") if r[c] == r[c] and r[c] > 0]
    if r["phi_wall"] == r["phi_wall"] and r["phi_wall"] > 0.1:
        out.append(f"phi_wall {r['phi_wall']:.2f}")
    if r["goal_reached"] != 1:
        out.append("no goal")
    return out


def _angle(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def _lane_heading(traj: pd.DataFrame, lane: str, t: float) -> float:
    """The heading SUMO's vehicles on ``lane`` have nearest to time ``t`` (its direction there), NaN if none."""
    on = traj[(traj["lane"] == lane) & (traj["id"] != "ego") & (traj["speed"] > 1.0)]
    if on.empty:
        return math.nan
    return float(on.iloc[(on["time_s"] - t).abs().argsort()[:1]]["heading"].iloc[0])


def _where(traj: pd.DataFrame, other: str, t: float, e) -> str:
    """Where ``other`` was from the ego's centre at ``t`` (along / across its heading) and its speed."""
    o = traj[(traj["id"] == other) & ((traj["time_s"] - t).abs() < 0.051)]
    if o.empty:
        return ""
    o = o.iloc[0]
    h = np.array([math.cos(e["heading"]), math.sin(e["heading"])])
    rel = np.array([o["x"] - e["x"], o["y"] - e["y"]])
    return (f"; {other} {rel @ h:+.1f} m along, {rel @ np.array([-h[1], h[0]]):+.1f} m across at "
            f"{o['speed']:.1f} m/s on {o['lane']}")


def contact_lines(m: dict, traj: pd.DataFrame) -> list[str]:
    out = []
    egos = set(traj.loc[traj["is_ego"].astype(bool), "id"])  # any ego id (an unseen district's egos are its cars)
    for ev in m.get("collision_events", []):
        me = ev["a"] if ev["a"] in egos else ev["b"]
        other = ev["b"] if me == ev["a"] else ev["a"]
        ego = traj[traj["id"] == me].set_index("time_s")
        t = round(ev["time_s"], 1)
        e = ego.iloc[(ego.index.to_series() - t).abs().argsort()[:1]].iloc[0]
        lane_h = _lane_heading(traj, e["lane"], t)
        skew = f"{math.degrees(_angle(e['heading'], lane_h)):.0f} deg to its lane" if lane_h == lane_h else "lane direction n/a"
        out.append(f"  ours  t={t:.1f} {other} ({ev.get('other_class', '?')}) {me} on {e['lane']} at "
                   f"{e['speed']:.1f} m/s, {skew}{_where(traj, other, t, e)}")
    for ev in m.get("sumo_collision_events", []):
        if egos & {ev["a"], ev["b"]}:
            out.append(f"  SUMO  t={ev['time_s']:.1f} {ev['a']}/{ev['b']} {ev['type']} on {ev['lane']} "
                       f"(collider {ev['collider']})")
    return out


def stand_lines(traj: pd.DataFrame) -> list[str]:
    ego = traj[traj["id"] == "ego"].sort_values("time_s")
    last = ego.iloc[-1]
    moving = ego[ego["speed"] > 0.3]
    since = float(moving["time_s"].max()) if len(moving) else float(ego["time_s"].min())
    end = traj[traj["time_s"] == last["time_s"]]
    h = np.array([math.cos(last["heading"]), math.sin(last["heading"])])
    rel = np.c_[end["x"] - last["x"], end["y"] - last["y"]]
    ahead, side = rel @ h, rel @ np.array([-h[1], h[0]])
    near = end.assign(ahead=ahead, side=side)
    near = near[(near["id"] != "ego") & (near["ahead"] > 0) & (near["ahead"] < 30) & (near["side"].abs() < 4)]
    near = near.sort_values("ahead").head(3)
    who = ", ".join(f"{r['id']} {r['ahead']:.0f} m ahead, {r['side']:+.1f} m across, {r['speed']:.1f} m/s on {r['lane']}"
                    for _, r in near.iterrows()) or "nothing within 30 m ahead and 4 m across"
    if last["time_s"] - since < 1.0:
        return [f"  still moving at the end of the run (t={last['time_s']:.1f}, {last['speed']:.1f} m/s on {last['lane']})"]
    return [f"  stood still from t={since:.1f} to the end ({last['time_s'] - since:.0f} s) on {last['lane']} at "
            f"({last['x']:.1f}, {last['y']:.1f}); ahead: {who}"]


def main(argv: list[str]) -> int:
    if len(argv) not in (1, 2):
        print("usage: python reports/cities/failures.py LEDGER.sqlite [CONTROLLER]", file=sys.stderr)
        return 2
    df = ledger.read(argv[0])
    base = pathlib.Path(argv[0]).resolve().parent
    ctrl = argv[1] if len(argv) == 2 else "apf_sa"
    df = df[df["controller"] == ctrl].sort_values(["scenario", "sensor", "seed"])
    for _, r in df.iterrows():
        sensor = "-" if r["controller"] == "sumo" else r["sensor"]  # SUMO's driver senses as SUMO does
        if r["status"] != "done":
            print(f"{r['scenario']} {sensor} seed {r['seed']}: run {r['status']}: {r['error']}")
            continue
        fails = _fails(r)
        if not fails:
            continue
        run = base / r["artifacts"]
        print(f"{r['scenario']} {sensor} seed {r['seed']} ({r['artifacts']}): {', '.join(fails)}")
        traj = pd.read_csv(run / "trajectories.csv")
        m = json.loads((run / "metrics.json").read_text())
        lines = contact_lines(m, traj)
        if r["goal_reached"] != 1:
            lines += stand_lines(traj)
        if lines:
            print("\n".join(lines))
    return 0


if __name__ == "__main__":
    from one_line import run

    run(main)
