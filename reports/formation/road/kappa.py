"""The road case's kappa against the geometry, per run of a batch ledger (docs/formation.md).

Usage: python reports/formation/road/kappa.py [reports/formation/road/ledger.sqlite]

Per done run of ``formation_road``: goal, collisions, phi_wall, kappa shares, and kappa while the
leader passes each place whose free width the closures fix (W = 8.8 m, gamma_min = 0.75):

* start (t < 5 s, the free road: gamma = 14 / 8.8 > 1)                    -> kappa 1;
* closure 1 (lanes 0-1 stopped, leader x 594-606 m: at most the 7.85 m from
  the stopped car in lane 1 to the left edge free, gamma <= 0.89 < 1)     -> kappa 2 or 3 (3 when
  traffic merging from the closed lanes narrows the gap further);
* closure 2 (lanes 0-2 stopped, leader x 994-1012 m: 4.35 m free, gamma <= 0.49 < gamma_min) -> kappa 3;
* the last 50 m before the goal (the free road again)                       -> kappa 1 (re-formed),
  and how far past closure 2 the leader was when kappa came back to 1.
"""
from __future__ import annotations

import json
import pathlib
import sqlite3
import sys

import numpy as np
import pandas as pd


def kappa_at(log, times):
    """kappa (1 before the first change) at each time of ``times`` from [[t, kappa], ...]."""
    t = np.array([0.0] + [a for a, _ in log])
    k = np.array([1] + [b for _, b in log])
    return k[np.searchsorted(t, np.asarray(times), side="right") - 1]


def seen(k, mask) -> str:
    """The kappa values taken where ``mask`` holds, e.g. '2/3' ('-' if none)."""
    return "/".join(str(v) for v in sorted(set(k[mask].tolist()))) or "-"


def main(ledger: pathlib.Path) -> int:
    con = sqlite3.connect(ledger)
    rows = con.execute("select seed, artifacts from runs where status = 'done' order by seed").fetchall()
    print("| seed | goal | T s | collisions | phi_wall m | kappa 1/2/3 share | start | closure 1 | closure 2 | "
          "last 50 m | kappa 1 again, m past closure 2 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for seed, art in rows:
        d = ledger.parent / art
        m = json.loads((d / "metrics.json").read_text())
        tr = pd.read_csv(d / "trajectories.csv")
        lead = tr[tr["id"] == "f0"]
        t, x = lead["time_s"].to_numpy(), lead["x"].to_numpy()
        k = kappa_at(m["formation_mode_log"], t)

        back = [a for a, b in m["formation_mode_log"] if b == 1 and np.interp(a, t, x) > 1012.0]
        past = f"{np.interp(back[0], t, x) - 1012.0:.0f}" if back else "never"
        print(f"| {seed} | {m['goal_reached']} | {m['formation_time_s']} | {m['collisions']} | {m['phi_wall']:.3f} | "
              f"{m['kappa1_share']:.2f}/{m['kappa2_share']:.2f}/{m['kappa3_share']:.2f} | {seen(k, t < 5.0)} | "
              f"{seen(k, (x >= 594) & (x <= 606))} | {seen(k, (x >= 994) & (x <= 1012))} | {seen(k, x >= 1450)} | {past} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "reports/formation/road/ledger.sqlite")))
