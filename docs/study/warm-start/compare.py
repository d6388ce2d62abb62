#!/usr/bin/env python3
"""Variants of the same points against a cold baseline (docs/study/warm-start/warm.sh).

    python3 docs/study/warm-start/compare.py BASELINE_DIR VARIANT_DIR [VARIANT_DIR ...] [--points] [--bands=N]

Points are matched by their index in results.csv. For each variant: CPU per point (median and
mean of each run's own cpu_time) and its ratio to the baseline's on the same points; over the
points where both flow (MFR >= 0.01 in both): the mean and RMS of z = ΔMFR / combined SE, the mean
relative difference (bias) with its standard error, the largest |z| and how many points pass
3 combined SE; the shared drift inside the variant's windows (last − first quarter over MFR,
averaged over its flowing points); and the warm-started points and their median distance.
--bands=N: a row per N consecutive design indices (a whole sweep run both ways: how the saving
and the error move as the design fills in).
"""
import csv, json, math, os, statistics, sys

def load(d):
    out = {}
    for r in csv.DictReader(open(os.path.join(d, "results.csv"))):
        if r["status"] not in ("done", "failed"):  # pending, running or screened: nothing ran
            continue
        run = os.path.join(d, "runs", r["hash"])
        j = {}
        for name in ("result.json", "failure.json"):
            f = os.path.join(run, name)
            if os.path.exists(f):
                j = json.load(open(f))
                j = j.get("measured") or j
        out[r["index"]] = dict(row=r, cpu=j.get("cpu_time") or float("nan"), steps=j.get("steps"),
                               warm=j.get("warm_start"), drift=(j.get("steady_state") or {}).get("drift"))
    return out

def num(s):
    return float(s) if s not in ("", None) else float("nan")

def mean(v):
    v = [x for x in v if not math.isnan(x)]
    return statistics.fmean(v) if v else float("nan")

def median(v):
    v = [x for x in v if not math.isnan(x)]
    return statistics.median(v) if v else float("nan")

def compare(base, var, name, show_points):
    zs, rel, cb, cv, drifts, dist = [], [], [], [], [], []
    if show_points:
        print(f"\n#### {name}\n\n| pt | D mm | gap mm | v m/s | μ | cold MFR ± SE | {name} MFR ± SE | z | steps | CPU s | from (distance) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
    for i in sorted(base, key=int):
        if i not in var:
            continue
        b, v = base[i], var[i]
        if not (math.isnan(b["cpu"]) or math.isnan(v["cpu"])):  # a run that failed has no CPU
            cb.append(b["cpu"]); cv.append(v["cpu"])
        mb, sb, mv, sv = num(b["row"]["mfr"]), num(b["row"]["mfr_se"]), num(v["row"]["mfr"]), num(v["row"]["mfr_se"])
        se = math.hypot(sb, sv)
        z = (mv - mb) / se if se > 0 else float("nan")
        flowing = mb >= 0.01 and mv >= 0.01 and b["row"]["status"] == v["row"]["status"] == "done"
        if flowing:
            zs.append(z); rel.append((mv - mb) / mb)
            if v["drift"] is not None:
                drifts.append(v["drift"])
        if v["warm"]:
            dist.append(v["warm"]["distance"])
        if show_points:
            r = b["row"]
            w = f"{v['warm']['from'][:8]} ({v['warm']['distance']:.2f})" if v["warm"] else "cold"
            print(f"| {i} | {num(r['diameter']):.2f} | {num(r['gap']):.2f} | {num(r['blade_speed']):.2f} | {num(r['friction']):.2f} | "
                  f"{mb:.4f} ± {sb:.4f} | {mv:.4f} ± {sv:.4f} ({v['row']['status']}) | {z:+.2f} | {b['steps']} → {v['steps']} | "
                  f"{b['cpu']:.1f} → {v['cpu']:.1f} | {w} |")
    n = len(zs)
    bias = statistics.fmean(rel) if rel else float("nan")
    bias_se = statistics.stdev(rel) / math.sqrt(n) if n > 1 else float("nan")
    drift = statistics.fmean(drifts) if drifts else float("nan")
    drift_se = statistics.stdev(drifts) / math.sqrt(len(drifts)) if len(drifts) > 1 else float("nan")
    big = sum(abs(z) > 3 for z in zs)
    print(f"| {name} | {len(cv)} | {median(cv):.2f} | {mean(cv):.2f} | {mean(cb) / mean(cv):.2f} | "
          f"{median(cb) / median(cv):.2f} | {n} | {statistics.fmean(zs) if zs else float('nan'):+.2f} | "
          f"{math.sqrt(statistics.fmean([z * z for z in zs])) if zs else float('nan'):.2f} | "
          f"{100 * bias:+.1f} ± {100 * bias_se:.1f} % | {max(map(abs, zs)) if zs else float('nan'):.2f} | {big} | "
          f"{100 * drift:+.1f} ± {100 * drift_se:.1f} % | {len(dist)} ({median(dist):.2f}) |")

def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    show = "--points" in sys.argv
    base = load(args[0])
    print(f"baseline {os.path.basename(os.path.normpath(args[0]))}: CPU s / point median {median([p['cpu'] for p in base.values()]):.2f}, "
          f"mean {mean([p['cpu'] for p in base.values()]):.2f}\n")
    print("| variant | points | CPU s median | mean | × cold (mean) | × cold (median) | flowing | mean z | RMS z | bias | max |z| | beyond 3 SE | drift | warm-started (median distance) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    bands = next((int(a.split("=")[1]) for a in sys.argv if a.startswith("--bands=")), None)
    for d in args[1:]:
        var, name = load(d), os.path.basename(os.path.normpath(d))
        if bands is None:
            compare(base, var, name, False)
            continue
        top = max(int(i) for i in var) + 1
        for lo in range(0, top, bands):
            band = lambda pts: {i: p for i, p in pts.items() if lo <= int(i) < lo + bands}
            if any(i in base for i in band(var)):
                compare(band(base), band(var), f"{name} [{lo}, {lo + bands})", False)
    if show:
        for d in args[1:]:
            compare(base, load(d), os.path.basename(os.path.normpath(d)), True)

if __name__ == "__main__":
    main()
