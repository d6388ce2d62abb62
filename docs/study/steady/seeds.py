#!/usr/bin/env python3
"""A point's MFR across pile seeds against the SE each run reports (docs/study/steady/seeds.sh).

For each point directory: the runs, the mean, the SD between seeds (n - 1), the mean reported
SE and their ratio, each run's z = (MFR - mean of the others) / sqrt(SE^2 + SD_others^2 / (n - 1)),
the excess kurtosis of the MFRs, and whether the windows a run took (a precision stop) go with
its distance from the mean.
    python3 docs/study/steady/seeds.py docs/study/steady/seeds/*
"""
import json
import math
import pathlib
import sys


def stats(x):
    n = len(x)
    m = sum(x) / n
    sd = math.sqrt(sum((v - m) ** 2 for v in x) / (n - 1))
    k = sum((v - m) ** 4 for v in x) / n / (sum((v - m) ** 2 for v in x) / n) ** 2 - 3
    return m, sd, k


for d in sys.argv[1:]:
    runs = []
    for f in sorted(pathlib.Path(d).glob("seed-*.json"), key=lambda p: int(p.stem.split("-")[1])):
        text = f.read_text()
        if not text.strip():
            continue
        r = json.loads(text)
        if "mfr" not in r:
            print(f"{f.name}: failed: {r.get('failure', r)}")
            continue
        runs.append((int(f.stem.split("-")[1]), r["mfr"], r["mfr_se"], len(r["mfr_windows"]), r["cpu_time"]))
    if len(runs) < 3:
        print(f"{d}: {len(runs)} runs")
        continue
    mfr = [r[1] for r in runs]
    se = [r[2] for r in runs]
    m, sd, kurt = stats(mfr)
    mse = sum(se) / len(se)
    print(f"{pathlib.Path(d).name}: {len(runs)} seeds, MFR {m:.4f}, SD between seeds {sd:.4f}, "
          f"mean reported SE {mse:.4f} (SD/SE {sd / mse:.2f}), excess kurtosis {kurt:+.2f}, "
          f"CPU {sum(r[4] for r in runs):.0f} s")
    zs = []
    for i, (seed, v, s, w, _) in enumerate(runs):
        others = mfr[:i] + mfr[i + 1:]
        mo, sdo, _ = stats(others)
        z = (v - mo) / math.sqrt(s * s + sdo * sdo / len(others))
        zs.append((abs(z), seed, v, s, w, z))
    beyond = [z for z in zs if z[0] > 2.5]
    rms = math.sqrt(sum(z[0] ** 2 for z in zs) / len(zs))
    print(f"  RMS z {rms:.2f}; |z| > 2.5: {len(beyond)} of {len(zs)} (a normal: {len(zs) * 0.0124:.1f})")
    for _, seed, v, s, w, z in sorted(zs, reverse=True)[:5]:
        print(f"  seed {seed:>3}: MFR {v:.4f} ± {s:.4f}, {w} windows, z {z:+.2f}")
    n = len(runs)
    mw = sum(r[3] for r in runs) / n
    dev = [abs(v - m) for v in mfr]
    md = sum(dev) / n
    cov = sum((r[3] - mw) * (e - md) for r, e in zip(runs, dev)) / n
    sw = math.sqrt(sum((r[3] - mw) ** 2 for r in runs) / n)
    sdv = math.sqrt(sum((e - md) ** 2 for e in dev) / n)
    print(f"  windows {min(r[3] for r in runs)}-{max(r[3] for r in runs)}; "
          f"correlation of windows with |MFR - mean|: {cov / (sw * sdv) if sw * sdv else float('nan'):+.2f}")
