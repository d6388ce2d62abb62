#!/usr/bin/env python3
"""The size study's record (record-size/, written by size.sh) as a table: per column size, the
pours done, the mean angle of repose and its scatter between seeds (SD, ddof 1) beside the SE
each pour reports over its heap's eight sectors (root mean square), the packing, and the CPU
seconds of a pour; then the CPU a mean to ±1° (one SE) costs at each size, (SD / 1°)² pours.

    python3 docs/study/calibration/size.py [record-size-2mm]   # from the repository's root
"""
import glob, json, math, os, re, statistics as st, sys

REC = os.path.join(os.path.dirname(os.path.abspath(__file__)), sys.argv[1] if len(sys.argv) > 1 else "record-size")
rows = {}
failed = []
for path in sorted(glob.glob(os.path.join(REC, "n*-s*.json"))):
    n, seed = map(int, re.match(r"n(\d+)-s(\d+)\.json", os.path.basename(path)).groups())
    j = json.load(open(path))
    if "failed" in j or not j.get("heap"):
        failed.append((n, seed, j.get("failed", "no heap")))
        continue
    h = j["heap"]
    rows.setdefault(n, []).append(dict(seed=seed, angle=h["angle_deg"], se=h["angle_se_deg"],
        packing=h["packing"], height=h["height_mm"], out=h["particles_run_out"],
        cpu=j.get("cpu_time") or float("nan"), steps=j.get("steps", 0)))

print("particles\tpours\tseeds\tangle_mean\tangle_sd_between\tse_of_mean\tsector_se_rms\tpacking_mean\tpacking_sd\theight_mm\tcpu_s_mean\tcpu_s_for_1deg")
for n in sorted(rows):
    r = rows[n]
    a = [x["angle"] for x in r]
    sd = st.stdev(a) if len(a) > 1 else float("nan")
    cpu = st.mean(x["cpu"] for x in r)
    p = [x["packing"] for x in r]
    print("\t".join([str(n), str(len(r)), ",".join(str(x["seed"]) for x in r),
        f"{st.mean(a):.2f}", f"{sd:.2f}", f"{sd / math.sqrt(len(a)):.2f}",
        f"{math.sqrt(st.mean(x['se'] ** 2 for x in r)):.2f}",
        f"{st.mean(p):.3f}", f"{st.stdev(p) if len(p) > 1 else float('nan'):.3f}",
        f"{st.mean(x['height'] for x in r):.3f}", f"{cpu:.0f}", f"{sd * sd * cpu:.0f}"]))
print()
print("particles\tseed\tangle_deg\tsector_se_deg\tpacking\theight_mm\trun_out\tcpu_s\tsteps")
for n in sorted(rows):
    for x in sorted(rows[n], key=lambda x: x["seed"]):
        print(f"{n}\t{x['seed']}\t{x['angle']:.2f}\t{x['se']:.2f}\t{x['packing']:.3f}\t{x['height']:.3f}\t{x['out']}\t{x['cpu']:.0f}\t{x['steps']}")
for n, seed, why in failed:
    print(f"{n}\t{seed}\tfailed: {why}")
