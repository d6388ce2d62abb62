# Whether the SE a real powder's point reports covers the scatter between seeds, at three speeds
# (docs/study/warmup-um.md "The SE between seeds at three speeds"): the point of
# sweeps/ti64-machine.toml at its defaults; 0.08 m/s from numerics.sh (`default`, seed 12345, and
# `seed2`…`seed10`), 0.02 and 0.2 m/s from seeds.sh (seeds 1–10). For each speed: the SD between
# seeds against the mean reported SE, each seed's z from the mean of the others, and the seeds
# against the long run of the same point without a warm-up (runs/ti64-v*-h0.4-g1e-4, its last
# half, as transient.py reads it).
#   python3 docs/study/warmup-um/seeds.py
import json, math, os, statistics

here = os.path.dirname(os.path.abspath(__file__))
GROUPS = [
    ("0.02", [os.path.join(here, "seeds", "v0.02", f"seed{k}.json") for k in range(1, 11)]),
    ("0.08", [os.path.join(here, "numerics", n + ".json") for n in ["default"] + [f"seed{k}" for k in range(2, 11)]]),
    ("0.2", [os.path.join(here, "seeds", "v0.2", f"seed{k}.json") for k in range(1, 11)]),
]


def se(y):
    """SE of the mean of y, widened for lag-1 autocorrelation (as transient.py)."""
    n, m, var = len(y), statistics.fmean(y), statistics.pvariance(y)
    r = sum((y[i] - m) * (y[i + 1] - m) for i in range(n - 1)) / (n * var) if var > 0 else 0.0
    r = min(max(r, 0.0), 0.8)
    return statistics.stdev(y) / math.sqrt(n) * math.sqrt((1 + r) / (1 - r))


def long_run(speed):
    f = os.path.join(here, "runs", f"ti64-v{speed}-h0.4-g1e-4", "result.json")
    y = json.load(open(f))["steady_state"]["block_mfr"]
    tail = y[len(y) // 2:]
    return statistics.fmean(tail), se(tail), len(tail)


rows, all_z = [], []
for speed, files in GROUPS:
    runs = [(os.path.basename(f)[:-5], json.load(open(f))) for f in files if os.path.exists(f)]
    if len(runs) < 3:
        print(f"{speed} m/s: {len(runs)} seeds recorded, too few to judge")
        continue
    m = [r["mfr"] for _, r in runs]
    s = [r["mfr_se"] for _, r in runs]
    cpu = [r["cpu_time"] for _, r in runs]
    n, mean, sd = len(m), statistics.fmean(m), statistics.stdev(m)
    print(f"\n{speed} m/s, {n} seeds: MFR {mean:.4f}, SD between seeds {sd:.4f}, mean reported SE "
          f"{statistics.fmean(s):.4f}, ratio {sd / statistics.fmean(s):.2f}; CPU {statistics.fmean(cpu):.0f} s a seed "
          f"({min(cpu):.0f}–{max(cpu):.0f})")
    zs = []
    lm, lse, lblocks = long_run(speed)
    within = 0
    short, longer = [], []
    for i, (name, r) in enumerate(runs):
        others = m[:i] + m[i + 1:]
        sdo = statistics.stdev(others)
        z = (m[i] - statistics.fmean(others)) / math.sqrt(s[i] ** 2 + sdo ** 2 / len(others))
        zs.append(z)
        zl = (m[i] - lm) / math.hypot(s[i], lse)
        within += abs(zl) <= 2
        st = r["steady_state"]
        window = st["window_blocks"]
        (short if window <= 12 else longer).append(zl)
        print(f"  {name:8s} {m[i]:.4f} ± {s[i]:.4f}  z {z:+.2f}  against the long run {zl:+.2f}  "
              f"window {window:3d} blocks  CPU {r['cpu_time']:.0f} s  {st['stop']}")
    all_z += zs
    rms = math.sqrt(sum(z * z for z in zs) / n)
    zmean = (mean - lm) / math.hypot(sd / math.sqrt(n), lse)
    print(f"  RMS z {rms:.2f}; the long run's last half ({lblocks} blocks) {lm:.4f} ± {lse:.4f}: "
          f"the seeds' mean {zmean:+.2f} combined SE from it, {within} of {n} seeds within 2 SE")
    for what, zz in [("windows of at most 12 blocks", short), ("longer windows", longer)]:
        if zz:
            print(f"  {what}: {len(zz)} seeds, RMS z against the long run {math.sqrt(sum(z * z for z in zz) / len(zz)):.2f}")
    rows.append((speed, n, mean, sd, statistics.fmean(s), rms, lm, lse, zmean, within, statistics.fmean(cpu)))

print("\n| v m/s | seeds | MFR (mean) | SD between seeds | mean reported SE | SD/SE | RMS z | long run, last half | seeds' mean from it (SE) | seeds within 2 SE of it | CPU s a seed |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for (v, n, mean, sd, mse, rms, lm, lse, zm, w, c) in rows:
    print(f"| {v} | {n} | {mean:.4f} | {sd:.4f} | {mse:.4f} | {sd / mse:.2f} | {rms:.2f} | {lm:.4f} ± {lse:.4f} | {zm:+.1f} | {w}/{n} | {c:.0f} |")
if all_z:
    print(f"\nall speeds: RMS z {math.sqrt(sum(z * z for z in all_z) / len(all_z)):.2f} over {len(all_z)} seeds")
