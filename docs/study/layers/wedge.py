"""Where along the plate a fused bed's steady passes lay their powder: the solid volume of the
last four passes' particles over each eighth of the plate's length, as a share of the whole, for
every finished point of a layers sweep directory (the dumps are in its run directories, not in
the records).  python3 docs/study/layers/wedge.py runs/machine-lattice > record/machine-lattice/wedge.txt"""
import glob
import json
import os
import sys

import numpy as np

BINS = 8
LAST = 4


def atoms(path):
    lines = open(path).read().split("\n")
    start = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS")) + 1
    return np.array([[float(v) for v in l.split()] for l in lines[start:] if l.strip()]).reshape(-1, 5)


sweep = sys.argv[1] if len(sys.argv) > 1 else "runs/machine-lattice"
print(f"# solid volume of the last {LAST} passes over each eighth of the plate (travel left to right), share of the whole")
print("layer_thickness_mm blade_speed_m_s " + " ".join(f"e{i + 1}" for i in range(BINS)) + " last_over_first_half")
rows = []
for run in sorted(glob.glob(os.path.join(sweep, "runs", "*", "result.json"))):
    d = os.path.dirname(run)
    r = json.load(open(run))
    n = len(r["layers"]["passes"])
    passes = [atoms(os.path.join(d, f"dump.layer.{k}")) for k in range(max(1, n - LAST + 1), n + 1)]
    x = np.concatenate([a[:, 1] for a in passes])
    x0, x1 = x.min(), x.max()
    vol = np.zeros(BINS)
    for a in passes:
        b = np.clip(((a[:, 1] - x0) / (x1 - x0) * BINS).astype(int), 0, BINS - 1)
        np.add.at(vol, b, a[:, 4] ** 3)
    share = vol / vol.sum()
    p = r["parameters"]
    rows.append((p["layer_thickness"], p["blade_speed"], share))
for t, v, s in sorted(rows, key=lambda r: (r[0], r[1])):
    ratio = s[BINS // 2 :].sum() / s[: BINS // 2].sum()
    print(f"{t:.3f} {v:.3f} " + " ".join(f"{x:.3f}" for x in s) + f" {ratio:.2f}")
