#!/usr/bin/env python3
"""A calibration directory's done pours as a table, in run order: the index, the named
parameters' values, the angle of repose with its sectors' SE, the heap's packing, the apparent
density (packing × the point's density, g/cm³) and the CPU seconds. The calibration scripts
beside it write their record's pours.tsv with it.

    python3 docs/study/calibration/pours.py DIR PARAMETER...   # e.g. friction rolling_friction
"""
import csv, json, os, sys

out, names = sys.argv[1], sys.argv[2:]
print("\t".join(["index", *names, "angle_deg", "angle_se_deg", "packing", "apparent_density_g_cm3", "cpu_s"]))
for r in csv.DictReader(open(os.path.join(out, "results.csv"))):
    path = os.path.join(out, "runs", r["hash"], "result.json")
    if r["status"] != "done" or not os.path.exists(path):
        continue
    j = json.load(open(path))
    h, p = j["heap"], j["parameters"]
    print("\t".join([r["index"], *(f"{float(p[n]):.4g}" for n in names), f"{h['angle_deg']:.2f}",
                     f"{h['angle_se_deg']:.2f}", f"{h['packing']:.3f}",
                     f"{p['density'] * h['packing'] / 1000:.3f}", f"{j.get('cpu_time', 0):.0f}"]))
