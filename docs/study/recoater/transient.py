#!/usr/bin/env python3
"""Where the conveyor's start-up transient ends, against travel, heap lengths and time.

    python3 docs/study/recoater/transient.py RUNS_DIR

For each case (a run directory with result.json or failure.json), MSER (White 1997) over the
whole block series: the first d blocks dropped where var(y_d..n)/(n - d) is least, d <= n/2.
The cut is given as blade travel in mm, in diameters and in heap lengths (the held heap's base,
(gap + heap_height) / tan 30°), and as time; then MFR over the rest with its batch-means SE.
"""
import glob, json, math, os, statistics, sys

def mser(y):
    n = len(y)
    best, best_v = 0, float("inf")
    for d in range(0, n // 2 + 1):
        w = y[d:]
        m = len(w)
        if m < 2:
            break
        v = statistics.pvariance(w) / m
        if v < best_v:
            best, best_v = d, v
    return best

def case_key(path):
    """(D, v, heap) from a case's name, D*-v* or D*-v*-h*."""
    parts = os.path.basename(path.rstrip("/")).split("-")
    d, v = float(parts[0][1:]), float(parts[1][1:])
    return (d, v, float(parts[2][1:]) if len(parts) > 2 else 20.0)

def main():
    runs = sys.argv[1]
    print("| D mm | v m/s | heap mm | blocks | MSER cut (blocks) | travel mm | travel D | heap lengths | time s | MFR ± SE (after the cut) | layer packing | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    cases = [c for c in glob.glob(os.path.join(runs, "D*-v*")) if os.path.isdir(c)]
    for case in sorted(cases, key=case_key):
        f = os.path.join(case, "result.json")
        status = "done"
        if not os.path.exists(f):
            f = os.path.join(case, "failure.json")
            if not os.path.exists(f):
                continue
        r = json.load(open(f))
        if "class" in r:
            status = r["class"]
            r = r.get("measured") or {}
        st = r.get("steady_state")
        if not st:
            print(f"| {case} | failed: {status} |")
            continue
        p = r["parameters"]
        d, v, gap, heap = p["diameter"], p["blade_speed"], p["gap"], p.get("heap_height", float("nan"))
        y = st["block_mfr"]
        cut = mser(y)
        block_mm = st["block_diameters"] * d
        travel = cut * block_mm
        heap_len = (gap + heap) / math.tan(math.radians(30))
        w = y[cut:]
        mean = statistics.fmean(w)
        se = statistics.stdev(w) / math.sqrt(len(w))
        packing = r.get("layer_packing")
        ratio = packing / r["mfr"] if packing and r["mfr"] else float("nan")
        print(f"| {d} | {v} | {heap:g} | {len(y)} | {cut} | {travel:.0f} | {travel / d:.0f} | {travel / heap_len:.2f} | {travel / 1e3 / v:.3f} | "
              f"{mean:.4f} ± {se:.4f} | {mean * ratio:.4f} | {r.get('cpu_time') or float('nan'):.0f} |")

if __name__ == "__main__":
    main()
