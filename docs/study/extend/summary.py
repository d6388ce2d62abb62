"""The CPU of extending a sweep against running its points again, from extend.sh's directories.

    python3 docs/study/extend/summary.py OUT
"""
import csv, json, math, sys
from pathlib import Path

out = Path(sys.argv[1])


def results(name):
    d = out / name
    rows = list(csv.DictReader(open(d / "results.csv")))
    return [json.load(open(d / "runs" / r["hash"] / "result.json")) if r["status"] == "done" else None for r in rows]


first, ext, fresh = results("first"), results("extended"), results("fresh")
print(f"| point | first: MFR ± SE, CPU s | extended: MFR ± SE, + CPU s | from rest: MFR ± SE, CPU s | z |")
print("|---|---|---|---|---|")
tot = [0.0, 0.0, 0.0]
zs = []
for i, (a, b, c) in enumerate(zip(first, ext, fresh)):
    if not (a and b and c):
        print(f"| {i} | failed in one of the three |")
        continue
    more = b["cpu_time"] - a["cpu_time"]
    tot[0] += a["cpu_time"]
    tot[1] += more
    tot[2] += c["cpu_time"]
    z = (b["mfr"] - c["mfr"]) / math.hypot(b["mfr_se"], c["mfr_se"])
    zs.append(z)
    cap = lambda r: " (cap)" if r["steady_state"]["stop"] == "cap" else ""
    print(
        f"| {i} | {a['mfr']:.4f} ± {a['mfr_se']:.4f}, {a['cpu_time']:.1f} | {b['mfr']:.4f} ± {b['mfr_se']:.4f}{cap(b)}, +{more:.1f}"
        f" | {c['mfr']:.4f} ± {c['mfr_se']:.4f}{cap(c)}, {c['cpu_time']:.1f} | {z:+.2f} |"
    )
rms = math.sqrt(sum(z * z for z in zs) / len(zs)) if zs else float("nan")
print(f"\nCPU: first {tot[0]:.0f} s; extension {tot[1]:.0f} s; from rest at the target {tot[2]:.0f} s")
print(f"extension / from rest = {tot[1] / tot[2]:.2f}; first + extension / (first + from rest) = {(tot[0] + tot[1]) / (tot[0] + tot[2]):.2f}")
print(f"extended against from rest: RMS z {rms:.2f} over {len(zs)} points")
