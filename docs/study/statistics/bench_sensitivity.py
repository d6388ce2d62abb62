#!/usr/bin/env python3
"""Cross-check `sweep`'s first-order sensitivity indices against SALib (BENCHMARKS.md
"Sensitivity indices").

    pip install SALib numpy
    python3 docs/study/statistics/bench_sensitivity.py [--sweep target/release/sweep]

1. Ishigami (a = 7, b = 0.1) on [-pi, pi]^3, known S1 = 0.3139, 0.4424, 0 (Saltelli 2008), on a
   random sample of N points (several seeds): `sweep stats --by` against SALib's RBD-FAST
   (`rbd_fast.analyze`) and delta (`delta.analyze`, its S1), both given-data estimators.
2. The same data as a real report: a stand-in LDS sweep over the thesis's 4-D space
   (sweeps/thesis-lds.toml with `[run] engine = "stand-in"`, 2,400 points), whose results.csv
   goes through `sweep stats --by` and both SALib estimators.
3. Intervals: on the first N = 100, 400 and 2,400 points of that sweep, our 95 % bootstrap
   interval of each index (`sweep stats --by`: lo, hi) beside SALib's delta S1 ± S1_conf (its
   bootstrap, 95 %), half-widths side by side.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from SALib.analyze import delta, rbd_fast

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
ISHIGAMI_S1 = [0.3139, 0.4424, 0.0]


def ishigami(x):
    return np.sin(x[:, 0]) + 7 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])


def ours(sweep, path, column, by):
    out = subprocess.run(
        [sweep, "stats", path, "--column", column, "--by", ",".join(by), "--json"],
        check=True, capture_output=True, text=True).stdout
    s = {d["parameter"]: d["first_order"] for d in json.loads(out)["sensitivity"]}
    return [s[b] for b in by]


def ours_intervals(sweep, path, column, by):
    out = subprocess.run(
        [sweep, "stats", path, "--column", column, "--by", ",".join(by), "--json"],
        check=True, capture_output=True, text=True).stdout
    s = {d["parameter"]: d for d in json.loads(out)["sensitivity"]}
    return [(s[b]["first_order"], s[b]["lo"], s[b]["hi"]) for b in by]


def salib(names, bounds, x, y, seed):
    problem = {"num_vars": len(names), "names": names, "bounds": bounds}
    r = rbd_fast.analyze(problem, x, y, seed=seed)
    d = delta.analyze(problem, x, y, seed=seed, num_resamples=10)
    return list(r["S1"]), list(d["S1"])


def fmt(v):
    return " ".join(f"{a:7.4f}" for a in v)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sweep", default=os.path.join(ROOT, "target/release/sweep"))
    ap.add_argument("--n", type=int, default=4000)
    ap.add_argument("--seeds", type=int, default=5)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="bench-sens-")

    print(f"Ishigami, N = {a.n} uniform random points, known S1 = {fmt(ISHIGAMI_S1)}")
    print("seed  estimator           S1(x1)  S1(x2)  S1(x3)   max |error|")
    errs = {"sweep": [], "rbd-fast": [], "delta": []}
    for seed in range(a.seeds):
        rng = np.random.default_rng(seed)
        x = rng.uniform(-math.pi, math.pi, size=(a.n, 3))
        y = ishigami(x)
        path = os.path.join(tmp, f"ishigami-{seed}.csv")
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["x1", "x2", "x3", "y"])
            for row, v in zip(x, y):
                w.writerow([repr(float(c)) for c in row] + [repr(float(v))])
        got = {"sweep": ours(a.sweep, path, "y", ["x1", "x2", "x3"])}
        got["rbd-fast"], got["delta"] = salib(["x1", "x2", "x3"], [[-math.pi, math.pi]] * 3, x, y, seed)
        for k, v in got.items():
            e = max(abs(g - t) for g, t in zip(v, ISHIGAMI_S1))
            errs[k].append(e)
            print(f"{seed:4d}  {k:18s} {fmt(v)}   {e:.4f}")
    for k, v in errs.items():
        print(f"mean max |error| {k:10s} {np.mean(v):.4f}")

    print("\nStand-in sweep over the thesis 4-D space (2,400 LDS points, all run: tolerance 0)")
    sweep_file = os.path.join(tmp, "thesis-lds-standin.toml")
    with open(os.path.join(ROOT, "sweeps/thesis-lds.toml")) as f:
        text = f.read()
    with open(sweep_file, "w") as f:
        f.write(text + '\n[run]\nengine = "stand-in"\n')
    out = os.path.join(tmp, "lds")
    subprocess.run([a.sweep, "lds", sweep_file, "--out", out, "-q", "--tolerance", "0", "--floor", "0"],
                   check=True, capture_output=True)
    names = ["friction", "diameter", "gap", "blade_speed"]
    bounds = [[0.1, 0.3], [1.0, 3.0], [1.0, 5.0], [1.2, 1.6]]
    with open(os.path.join(out, "results.csv"), newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["status"] == "done"]
    x = np.array([[float(r[n]) for n in names] for r in rows])
    y = np.array([float(r["mfr"]) for r in rows])
    mine = ours(a.sweep, os.path.join(out, "results.csv"), "mfr", names)
    r, d = salib(names, bounds, x, y, 0)
    print(f"N = {len(rows)}; parameters: {' '.join(f'{n:>11s}' for n in names)}")
    for k, v in [("sweep", mine), ("rbd-fast", r), ("delta", d)]:
        print(f"  {k:18s} " + " ".join(f"{c:11.4f}" for c in v))

    print("\nIntervals (95 %): ours [lo, hi] (half-width) against SALib delta S1 ± S1_conf")
    problem = {"num_vars": 4, "names": names, "bounds": bounds}
    for n in [100, 400, len(rows)]:
        path = os.path.join(tmp, f"first-{n}.csv")
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(names + ["mfr"])
            for row, v in zip(x[:n], y[:n]):
                w.writerow([repr(float(c)) for c in row] + [repr(float(v))])
        mine = ours_intervals(a.sweep, path, "mfr", names)
        dd = delta.analyze(problem, x[:n], y[:n], seed=0, num_resamples=100)
        print(f"N = {n}")
        for k, nm in enumerate(names):
            s1, lo, hi = mine[k]
            print(f"  {nm:11s} ours {s1:.3f} [{lo:.3f}, {hi:.3f}] (±{(hi - lo) / 2:.3f})   "
                  f"delta {dd['S1'][k]:.3f} ± {dd['S1_conf'][k]:.3f}")


if __name__ == "__main__":
    sys.exit(main())
