#!/usr/bin/env python3
"""CPU of sweep directories' runs against the first one's on the same design indices.

    python3 docs/study/thesis/lds_cost.py BASE_DIR [DIR ...]

Per directory: the runs with a CPU time (done or failed), their mean and median CPU s, the mean
over the indices the base also ran against the base's mean there, and the CPU-hours of the
thesis LDS's 2,304 runs (2,400 points less the 96 its screen closes) at that mean.
"""
import csv, json, os, statistics, sys
def load(d):
    out = {}
    for r in csv.DictReader(open(os.path.join(d, "results.csv"))):
        if r["status"] not in ("done", "failed"):
            continue
        for n in ("result.json", "failure.json"):
            f = os.path.join(d, "runs", r["hash"], n)
            if os.path.exists(f):
                j = json.load(open(f)); j = j.get("measured") or j
                if j.get("cpu_time"):
                    out[int(r["index"])] = j["cpu_time"]
    return out
base = load(sys.argv[1])
for d in sys.argv[1:]:
    v = load(d)
    common = [i for i in v if i in base]
    mv = statistics.fmean(v[i] for i in common)
    print(f"{os.path.basename(d.rstrip('/'))}: runs {len(v)}, CPU mean {statistics.fmean(v.values()):.2f} median {statistics.median(v.values()):.2f}; "
          f"on {len(common)} shared: mean {mv:.2f} vs base {statistics.fmean(base[i] for i in common):.2f}; 2,304 runs -> {2304*statistics.fmean(v.values())/3600:.2f} CPU-h")
