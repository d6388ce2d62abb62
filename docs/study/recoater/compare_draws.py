#!/usr/bin/env python3
"""Two sweep directories over the same points: CPU per point and MFR, point by point.

    python3 docs/study/recoater/compare_draws.py BEFORE_DIR AFTER_DIR

Points are matched by their index in results.csv; CPU seconds are each run's own (result.json's
cpu_time, or failure.json's measured one). A point's MFRs agree when they differ by at most
2 combined SE.
"""
import csv, json, math, os, statistics, sys

def load(d):
    rows = {r["index"]: r for r in csv.DictReader(open(os.path.join(d, "results.csv")))}
    out = {}
    for i, r in rows.items():
        run = os.path.join(d, "runs", r["hash"])
        cpu = float("nan")
        for name in ("result.json", "failure.json"):
            f = os.path.join(run, name)
            if os.path.exists(f):
                j = json.load(open(f))
                j = j.get("measured") or j
                cpu = j.get("cpu_time") or cpu
                steps = j.get("steps")
        out[i] = (r, cpu, steps)
    return out

def num(s):
    return float(s) if s not in ("", None) else float("nan")

def main():
    before, after = load(sys.argv[1]), load(sys.argv[2])
    print("| pt | D mm | gap mm | v m/s | μ | before MFR ± SE | after MFR ± SE | Δ / combined SE | steps before → after | CPU s before | after |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    cb, ca, off = [], [], []
    for i in sorted(before, key=int):
        (rb, cpub, sb), (ra, cpua, sa) = before[i], after[i]
        mb, sb_, ma, sa_ = num(rb["mfr"]), num(rb["mfr_se"]), num(ra["mfr"]), num(ra["mfr_se"])
        se = math.hypot(sb_, sa_)
        z = (ma - mb) / se if se > 0 else (0.0 if ma == mb else float("inf"))
        if abs(z) > 2:
            off.append(i)
        cb.append(cpub); ca.append(cpua)
        print(f"| {i} | {num(rb['diameter']):.2f} | {num(rb['gap']):.2f} | {num(rb['blade_speed']):.2f} | {num(rb['friction']):.2f} | "
              f"{mb:.4f} ± {sb_:.4f} ({rb['status']}) | {ma:.4f} ± {sa_:.4f} ({ra['status']}) | {z:+.2f} | {sb} → {sa} | {cpub:.1f} | {cpua:.1f} |")
    mb, ma = statistics.fmean(cb), statistics.fmean(ca)
    print(f"\nCPU s / point: before {mb:.2f}, after {ma:.2f}, ratio before/after {mb / ma:.2f}; "
          f"points beyond 2 combined SE: {len(off)} ({', '.join(off) or 'none'})")

if __name__ == "__main__":
    main()
