#!/usr/bin/env python3
"""Summarise the steady-state measurement over a sweep directory (conveyor layout).

    python3 docs/study/steady/steady_study.py DIR [--csv OUT.csv]

Per point: parameters, MFR ± SE, transient and window (blocks), trend z, drift (last quarter −
first quarter over MFR), heap start/end/target, stop, CPU s. Then the checks of the shared
drift, the trends beyond 2 SE, the heap, the median relative SE and the CPU.
"""
import csv, glob, json, os, statistics, sys

def rows(d):
    for f in sorted(glob.glob(os.path.join(d, "runs", "*", "result.json")) + glob.glob(os.path.join(d, "runs", "*", "failure.json"))):
        r = json.load(open(f))
        status = "done"
        if "class" in r:
            status = r["class"]
            r = r.get("measured") or {}
            if not r:
                continue
        s = r.get("steady_state") or {}
        w = r.get("mfr_windows") or []
        p = r["parameters"]
        yield dict(status=status, D=p["diameter"], gap=p["gap"], v=p["blade_speed"], mu=p["friction"],
                   mfr=r["mfr"], se=r.get("mfr_se"), transient=s.get("transient_blocks"), window=s.get("window_blocks"),
                   trend_z=s.get("trend_z"), drift=s.get("drift") if r["mfr"] > 0 else None,
                   heap_start=s.get("heap_start"), heap_end=s.get("heap_end"), heap_target=s.get("heap_target"),
                   stop=s.get("stop"), cpu=r.get("cpu_time"), steps=r["steps"])

def main():
    d = sys.argv[1]
    rs = list(rows(d))
    if "--csv" in sys.argv:
        out = sys.argv[sys.argv.index("--csv") + 1]
        with open(out, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rs[0].keys()))
            w.writeheader()
            w.writerows(rs)
    flowing_all = [r for r in rs if r["mfr"] > 0 and r["drift"] is not None]
    # A point depositing a handful of particles (MFR < 0.01) has a drift of pure counting noise.
    flowing = [r for r in flowing_all if r["mfr"] >= 0.01]
    print(f"points {len(rs)}: done {sum(r['status']=='done' for r in rs)}, MFR > 0: {len(flowing_all)}, MFR >= 0.01: {len(flowing)}")
    if flowing:
        drifts = [r["drift"] for r in flowing]
        m = statistics.mean(drifts)
        se = statistics.stdev(drifts) / len(drifts) ** 0.5 if len(drifts) > 1 else float("nan")
        print(f"shared drift (last − first quarter)/MFR: {100*m:+.1f} ± {100*se:.1f} % (limit ±5 %)")
        beyond = sum(abs(r["trend_z"]) > 2 for r in flowing)
        print(f"trend beyond 2 SE: {beyond}/{len(flowing)} ({100*beyond/len(flowing):.0f} %, limit 10 %)")
        rel = [r["se"] / r["mfr"] for r in flowing]
        print(f"relative SE: median {100*statistics.median(rel):.1f} %, max {100*max(rel):.1f} %")
    heap = [abs(r["heap_end"] - r["heap_start"]) / r["heap_start"] for r in rs if r["heap_start"]]
    if heap:
        print(f"heap change start→end: max {100*max(heap):.1f} % (limit 10 %)")
    cpu = [r["cpu"] for r in rs if r["cpu"]]
    if cpu:
        print(f"CPU s per point: median {statistics.median(cpu):.1f}, mean {statistics.mean(cpu):.1f}, max {max(cpu):.1f}")
    stops = {}
    for r in rs:
        stops[r["stop"]] = stops.get(r["stop"], 0) + 1
    print(f"stop: {stops}")

main()
