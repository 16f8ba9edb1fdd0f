"""Per-seed Markdown table of a flock batch from the runs CSV that `sumo-avoid report --csv` writes.

    python reports/flock_roads/per_seed.py reports/flock_roads/runs.csv
"""
import sys

import pandas as pd

COLS = ["collisions", "sumo_collisions", "phi_wall", "off_road_m", "wrong_way_m", "min_gap_m", "min_ttc2d_s",
        "mean_speed_mps", "v_vel", "phi_corr", "n_min", "max_lat_accel_mps2"]

runs = pd.read_csv(sys.argv[1])
for scenario, g in runs.sort_values(["scenario", "seed"]).groupby("scenario", sort=True):
    print(f"\n**{scenario}** ({len(g)} runs, {int((g['status'] == 'done').sum())} done)\n")
    print("| seed | status | " + " | ".join(COLS) + " |")
    print("|---" * (len(COLS) + 2) + "|")
    for _, r in g.iterrows():
        vals = [("" if pd.isna(r.get(c)) else f"{r[c]:.3g}" if isinstance(r[c], float) else str(r[c])) for c in COLS]
        print(f"| {r['seed']} | {r['status']} | " + " | ".join(vals) + " |")
