"""Compare two suite ledgers row by row (scenario, controller, seed) on every result column."""
import sqlite3, sys
import numpy as np, pandas as pd
SKIP = {"key", "scenario_path", "net_file", "started_at", "ended_at", "wall_s", "overhead_s", "artifacts", "code", "overrides"}
def load(p):
    c = sqlite3.connect(p); df = pd.read_sql("select * from runs", c); c.close()
    return df.set_index(["scenario", "controller", "seed"]).sort_index()
a, b = load(sys.argv[1]), load(sys.argv[2])
cols = [c for c in a.columns if c in b.columns and c not in SKIP]
only = sorted(set(a.columns) ^ set(b.columns))
assert list(a.index) == list(b.index), "different runs"
diff = []
for c in cols:
    x, y = a[c], b[c]
    same = (x == y) | (x.isna() & y.isna())
    for idx in x.index[~same]:
        diff.append((idx, c, x[idx], y[idx]))
print(f"{len(a)} rows, {len(cols)} columns compared; columns in one ledger only: {only}")
print(f"differing cells: {len(diff)}")
for d in diff[:40]:
    print(d)
