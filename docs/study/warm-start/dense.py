#!/usr/bin/env python3
"""The last 24 points of the dense run (warm.sh with DENSE=N) against their long cold runs.

    python3 docs/study/warm-start/dense.py WORK_DIR

Per point: MFR ± SE on the defaults and in the long run, z = Δ / combined SE, the neighbour's
distance and the point's CPU; then the mean z, the bias (mean relative difference ± SE), the
largest |z|, the points past 3 SE, and the median CPU against the long runs' and the cold draw's.
"""
import csv, glob, json, math, os, statistics, sys

work = sys.argv[1]
dense = {r["index"]: r for r in csv.DictReader(open(os.path.join(work, "thesis-dense", "results.csv")))}
zs, rel, cpu, lcpu, dist = [], [], [], [], []
print("| pt | D mm | gap mm | v m/s | μ | long MFR ± SE | default MFR ± SE | z | distance | CPU s default | long |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for f in sorted(glob.glob(os.path.join(work, "thesis-dense-long", "*.json")), key=lambda p: int(os.path.basename(p).split(".")[0])):
    i = os.path.basename(f).split(".")[0]
    try:
        long = json.load(open(f))
    except ValueError:
        continue
    long = long.get("measured") or long
    r = dense[i]
    res = json.load(open(os.path.join(work, "thesis-dense", "runs", r["hash"], "result.json")))
    m, s, lm, ls = float(r["mfr"]), float(r["mfr_se"] or 0), long["mfr"], long.get("mfr_se") or 0
    se = math.hypot(s, ls)
    z = (m - lm) / se if se > 0 else float("nan")
    d = (res.get("warm_start") or {}).get("distance")
    if lm >= 0.01 and m >= 0.01:
        zs.append(z); rel.append((m - lm) / lm)
    cpu.append(res["cpu_time"]); lcpu.append(long.get("cpu_time") or float("nan"))
    if d is not None:
        dist.append(d)
    print(f"| {i} | {float(r['diameter']):.2f} | {float(r['gap']):.2f} | {float(r['blade_speed']):.2f} | {float(r['friction']):.2f} | "
          f"{lm:.4f} ± {ls:.4f} | {m:.4f} ± {s:.4f} | {z:+.2f} | {'cold' if d is None else f'{d:.2f}'} | {res['cpu_time']:.1f} | {long.get('cpu_time', float('nan')):.1f} |")
n = len(zs)
print(f"\n{len(cpu)} points, {n} flowing: mean z {statistics.fmean(zs):+.2f}, bias {100 * statistics.fmean(rel):+.1f} ± "
      f"{100 * statistics.stdev(rel) / math.sqrt(n):.1f} %, max |z| {max(map(abs, zs)):.2f}, beyond 3 SE {sum(abs(z) > 3 for z in zs)}; "
      f"median distance {statistics.median(dist):.2f}; CPU s median {statistics.median(cpu):.2f}, mean {statistics.fmean(cpu):.2f}")
