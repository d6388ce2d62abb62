#!/usr/bin/env python3
"""The answer's cost on LIGGGHTS: each way's answer against the truth, and the CPU it took.

    python3 docs/study/answer-cost-1d/summary.py OUT      # OUT as given to run.sh
    python3 docs/study/answer-cost-1d/summary.py OUT --keep docs/study/answer-cost-1d/record
    python3 docs/study/answer-cost-1d/summary.py docs/study/answer-cost-1d/record

The truth is the 33-point lattice (OUT/truth) read as `sweep lattice` reports it (trapezoid
weights over the speed). Targets, as in BENCHMARKS.md "Designs against a known answer": mean
within 2 %, std within 3 %, skewness and kurtosis within 5 % of their scale (the rule's scales:
max(|skewness|, 1) and the kurtosis), and the recommended setting's true MFR (the truth lattice
interpolated) within one SE of the truth's recommended run. CPU is LIGGGHTS's own (each run's
`cpu_time`), summed over the runs of the design up to a space, in design order.
"""
import csv
import gzip
import json
import re
import subprocess
import sys
from pathlib import Path

def opened(path):
    """`path`, or its gzipped copy `path.gz` (how the kept record stores the larger files)."""
    path = Path(path)
    if not path.is_file() and path.with_name(path.name + ".gz").is_file():
        return gzip.open(path.with_name(path.name + ".gz"), "rt")
    return open(path)


TARGETS = {"mean": 0.02, "std": 0.03, "skewness": 0.05, "kurtosis": 0.05}


def scale(stat, m):
    if stat == "mean":
        return abs(m["mean"])
    if stat == "std":
        return m["std"]
    if stat == "skewness":
        return max(abs(m["skewness"]), 1.0)
    return m["kurtosis"]


def rows(d):
    with opened(d / "results.csv") as f:
        return sorted(csv.DictReader(f), key=lambda r: int(r["index"]))


def cpu(d, r):
    """A run's CPU s: its result.json, or in a kept record (no runs/) the way's cpu.csv."""
    p = d / "runs" / r["hash"] / "result.json"
    if r["hash"] and p.is_file():
        return json.load(open(p)).get("cpu_time", 0.0)
    kept = d / "cpu.csv"
    if kept.is_file():
        return next((float(k["cpu_time"]) for k in csv.DictReader(open(kept)) if k["hash"] == r["hash"]), 0.0)
    return 0.0


def keep(out, record):
    """Copy what this summary reads into `record` (no run directories): each way's results.csv,
    summary.json and cpu.csv, and the truth's emulator cache."""
    import shutil
    record.mkdir(parents=True, exist_ok=True)
    for way in ["truth", "thesis", "lds", "adapt"]:
        d, r = out / way, record / way
        r.mkdir(exist_ok=True)
        for f in ["results.csv", "summary.json"]:
            with open(d / f, "rb") as src, gzip.open(r / (f + ".gz"), "wb") as dst:
                shutil.copyfileobj(src, dst)
        for f in ["batches.csv", "precision.json"]:
            if (d / f).is_file():
                shutil.copy(d / f, r / f)
        with open(r / "cpu.csv", "w") as f:
            f.write("hash,cpu_time\n")
            for row in rows(d):
                f.write(f"{row['hash']},{cpu(d, row)}\n")
    for f in ["truth-emulator.json", "thesis.toml", "truth.toml", "speed.toml", "exits.txt"]:
        if (out / f).is_file():
            shutil.copy(out / f, record / f)


def recommended(d, summary):
    """The recommended run's blade speed, from the answer's "(point #k)"."""
    m = re.search(r"point #(\d+)", summary["answer"]["recommendation"] or "")
    if not m:
        return None
    for r in rows(d):
        if r["index"] == m.group(1):
            return float(r["blade_speed"]), float(r["mfr"]), float(r["mfr_se"] or "nan")
    return None


def interpolate(truth, v):
    pts = sorted((float(r["blade_speed"]), float(r["mfr"])) for r in truth if r["status"] == "done")
    for (v0, y0), (v1, y1) in zip(pts, pts[1:]):
        if v0 <= v <= v1:
            return y0 + (y1 - y0) * (v - v0) / (v1 - v0)
    return pts[0][1] if v < pts[0][0] else pts[-1][1]


def emulator_truth(truth_dir, lo=0.2, hi=1.4, n=201):
    """The four statistics of the truth's emulator mean over the speed (uniform), from `sweep
    predict` at n evenly spaced speeds (cached in OUT/truth-emulator.json): a cross-check of
    the lattice's quadrature that smooths the runs' noise."""
    cache = truth_dir.parent / "truth-emulator.json"
    if cache.is_file():
        ys = json.load(open(cache))
    else:
        ys = []
        for k in range(n):
            v = lo + (hi - lo) * k / (n - 1)
            o = subprocess.run(["sweep", "predict", str(truth_dir), "--set", f"blade_speed={v}", "--json"],
                               capture_output=True, text=True, check=True)
            ys.append(json.loads(o.stdout)["mfr"])
        json.dump(ys, open(cache, "w"))
    m = sum(ys) / len(ys)
    sd = (sum((y - m) ** 2 for y in ys) / len(ys)) ** 0.5
    med = sorted(ys)[len(ys) // 2]
    return {"mean": m, "std": sd, "skewness": 3 * (m - med) / sd,
            "kurtosis": sum((y - m) ** 4 for y in ys) / len(ys) / sd ** 4}


def truth_resolution(truth_rows, replicates=400):
    """How well the truth itself knows each statistic: its lattice's MFRs perturbed by their own
    SEs (normal, seeded), interpolated linearly over 2,001 speeds; the SD of each statistic."""
    import random
    import statistics
    pts = sorted((float(r["blade_speed"]), float(r["mfr"]), float(r["mfr_se"]))
                 for r in truth_rows if r["status"] == "done")

    def moments(vals):
        lo, hi = vals[0][0], vals[-1][0]
        ys, j = [], 0
        for k in range(2001):
            x = lo + (hi - lo) * k / 2000
            while j < len(vals) - 2 and vals[j + 1][0] < x:
                j += 1
            (x0, y0), (x1, y1) = vals[j], vals[j + 1]
            ys.append(y0 + (y1 - y0) * (x - x0) / (x1 - x0))
        m = sum(ys) / len(ys)
        sd = (sum((y - m) ** 2 for y in ys) / len(ys)) ** 0.5
        med = sorted(ys)[len(ys) // 2]
        return {"mean": m, "std": sd, "skewness": 3 * (m - med) / sd,
                "kurtosis": sum((y - m) ** 4 for y in ys) / len(ys) / sd ** 4}

    rng = random.Random(1)
    reps = [moments([(v, y + rng.gauss(0, se)) for v, y, se in pts]) for _ in range(replicates)]
    return {k: statistics.stdev(r[k] for r in reps) for k in TARGETS}


def main(out):
    out = Path(out)
    truth_dir = out / "truth"
    ts = json.load(opened(truth_dir / "summary.json"))
    truth = ts["statistics"]
    truth_rows = rows(truth_dir)
    best = recommended(truth_dir, ts)
    truth_cpu = sum(cpu(truth_dir, r) for r in truth_rows)
    print(f"Truth: {len(truth_rows)}-point lattice, {truth_cpu:.0f} CPU s; mean {truth['mean']:.4f}, "
          f"std {truth['std']:.4f}, skewness {truth['skewness']:.3f}, kurtosis {truth['kurtosis']:.3f}; "
          f"verdict {ts['verdict']['status']}")
    em = emulator_truth(truth_dir)
    print("The truth's emulator over 201 speeds (a cross-check): " + ", ".join(
        f"{k} {em[k]:.4g} ({(em[k] - truth[k]) / scale(k, truth):+.1%} of the scale)" for k in TARGETS))
    res = truth_resolution(truth_rows)
    print("The truth's own resolution (SD from its runs' SEs): " + ", ".join(
        f"{k} ±{res[k]:.4g} ({res[k] / scale(k, truth):.1%} of the scale)" for k in TARGETS))
    if best:
        print(f"Truth's recommendation: blade_speed {best[0]:.3f} m/s, MFR {best[1]:.4f} ± {best[2]:.4f}")
    print()
    print("| way | runs | verdict (at runs) | CPU s to the end | CPU s a run | mean | std | skewness | kurtosis | recommended m/s (true MFR) | targets met |")
    print("|---|---:|---|---:|---:|---|---|---|---|---|---|")
    for way in ["thesis", "lds", "adapt"]:
        d = out / way
        if not (d / "summary.json").is_file() and not (d / "summary.json.gz").is_file():
            print(f"| {way} | (running) |")
            continue
        s = json.load(opened(d / "summary.json"))
        rs = rows(d)
        if s["counts"]["points"] != len(rs) or any(r["status"] == "pending" for r in rs):
            print(f"| {way} | (running: {sum(r['status'] != 'pending' for r in rs)} of {len(rs)} planned) |")
            continue
        done = [r for r in rs if r["status"] in ("done", "failed", "screened")]
        total = sum(cpu(d, r) for r in done)
        m = s["statistics"]
        cells, met = [], 0
        for stat, tol in TARGETS.items():
            err = (m[stat] - truth[stat]) / scale(stat, truth)
            ok = abs(err) <= tol
            met += ok
            cells.append(f"{m[stat]:.4g} ({err:+.1%}{' ✓' if ok else ''})")
        rec = recommended(d, s)
        if rec and best:
            true_mfr = interpolate(truth_rows, rec[0])
            ok = abs(true_mfr - best[1]) <= best[2]
            met += ok
            cells.append(f"{rec[0]:.3f} ({true_mfr:.4f}{' ✓' if ok else ''})")
        else:
            cells.append("–")
        v = s["verdict"]
        verdict = f"{v['status']}" + (f" ({v['n']})" if v.get("n") else "")
        print(f"| {way} | {len(done)} | {verdict} | {total:.0f} | {total / max(len(done), 1):.1f} | "
              + " | ".join(cells) + f" | {met}/5 |")


def for_good(out, truth):
    """Per way: the runs (and CPU s) from which each statistic's target holds at every later
    space the sweep judged."""
    print()
    print("Runs (CPU s) from which each target holds at every later space:")
    print()
    print("| way | " + " | ".join(f"{k} ±{t:.0%}" for k, t in TARGETS.items()) + " | all four |")
    print("|---|" + "---:|" * (len(TARGETS) + 1))
    for way in ["thesis", "lds", "adapt"]:
        d = out / way
        if not (d / "summary.json").is_file() and not (d / "summary.json.gz").is_file():
            continue
        s = json.load(opened(d / "summary.json"))
        rs = rows(d)
        spent, cum = 0.0, [0.0]
        for r in rs:
            spent += cpu(d, r)
            cum.append(spent)
        spaces = [(sp["n"], sp["statistics"]) for sp in s["spaces"] if sp.get("statistics")]
        cells, firsts = [], []
        for k, tol in TARGETS.items():
            first = None
            for n, m in reversed(spaces):
                if m.get(k) is None or abs(m[k] - truth[k]) / scale(k, truth) > tol:
                    break
                first = n
            firsts.append(first)
            cells.append("never" if first is None else f"{first} ({cum[min(first, len(rs))]:.0f})")
        last = None if None in firsts else max(firsts)
        cells.append("never" if last is None else f"{last} ({cum[min(last, len(rs))]:.0f})")
        print(f"| {way} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/answer-cost-1d")
    if len(sys.argv) > 3 and sys.argv[2] == "--keep":
        keep(out, Path(sys.argv[3]))
        out = Path(sys.argv[3])
    main(out)
    for_good(out, json.load(opened(out / "truth" / "summary.json"))["statistics"])
