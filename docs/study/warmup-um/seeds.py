# Whether the SE a real powder's point reports covers the scatter between seeds, at four speeds
# (docs/study/warmup-um.md "The SE between seeds at four speeds"): the point of
# sweeps/ti64-machine.toml at its defaults, ten scene seeds a speed — 0.02 m/s from seeds.sh,
# 0.063 and 0.2 m/s from docs/study/steady/seeds.sh (`steady/seeds/ti64-v*`), 0.08 m/s from
# numerics.sh (`default`, seed 12345, and `seed2`…`seed10`). For each speed: the SD between
# seeds against the mean reported SE, each seed's z from the mean of the others, and, where
# there is one, the seeds against the long run of the same point without a warm-up
# (runs/ti64-v*-h0.4-g1e-4, its last half, as transient.py reads it).
#   python3 docs/study/warmup-um/seeds.py
import json, math, os, statistics

here = os.path.dirname(os.path.abspath(__file__))
steady = os.path.join(here, "..", "steady", "seeds")
GROUPS = [
    ("0.02", [os.path.join(here, "seeds", "v0.02", f"seed{k}.json") for k in range(1, 11)]),
    ("0.063", [os.path.join(steady, "ti64-v0.063", f"seed-{k}.json") for k in range(1, 11)]),
    ("0.08", [os.path.join(here, "numerics", n + ".json") for n in ["default"] + [f"seed{k}" for k in range(2, 11)]]),
    ("0.2", [os.path.join(steady, "ti64-v0.2", f"seed-{k}.json") for k in range(1, 11)]),
]
# The same points again once the SE was widened by Student's t and the deck stopped on it
# (docs/study/steady/seeds.sh … ti64-v0.063-t, ti64-v0.2-t, ti64-v0.08-t): rows "0.063 t" etc.
GROUPS += [(f"{v} t", [os.path.join(steady, f"ti64-v{v}-t", f"seed-{k}.json") for k in range(1, 11)])
           for v in ("0.063", "0.08", "0.2")]

def se(y):
    """SE of the mean of y, widened for lag-1 autocorrelation (as transient.py)."""
    n, m, var = len(y), statistics.fmean(y), statistics.pvariance(y)
    r = sum((y[i] - m) * (y[i + 1] - m) for i in range(n - 1)) / (n * var) if var > 0 else 0.0
    r = min(max(r, 0.0), 0.8)
    return statistics.stdev(y) / math.sqrt(n) * math.sqrt((1 + r) / (1 - r))


def long_run(label):
    f = os.path.join(here, "runs", f"ti64-v{label.split()[0]}-h0.4-g1e-4", "result.json")
    if not os.path.exists(f):
        return None
    y = json.load(open(f))["steady_state"]["block_mfr"]
    tail = y[len(y) // 2:]
    return statistics.fmean(tail), se(tail), len(tail)


def t_allowance(dof):
    """t_0.975(dof) / 1.96 by three terms of its Cornish-Fisher series (src/measure/steady.rs)."""
    u = 1.0 / dof
    return 1 + u * (1.21037 + u * (1.4401 + u * 1.3041))


def batch_se(y):
    """Batch-means SE and batch count, as src/measure/steady.rs batch_means_se."""
    b = 1
    while True:
        means = [statistics.fmean(y[i:i + b]) for i in range(0, len(y) - b + 1, b)]
        m = statistics.fmean(means)
        var = sum((v - m) ** 2 for v in means)
        r = sum((means[i] - m) * (means[i + 1] - m) for i in range(len(means) - 1)) / var if var > 0 else 0.0
        if r <= 0.2 or len(y) // (2 * b) < 8:
            return statistics.stdev(means) / math.sqrt(len(means)), len(means)
        b *= 2


def widened_offline(r):
    """A run of the rule before, its SE widened by t as a result now reports it: the warm-up is
    the start whose batch-means SE over the settled blocks, scaled to the window, is the one
    the run reported; the widening is for that SE's batches less one."""
    st = r["steady_state"]
    y, window = st["block_mfr"], st["window_blocks"]
    best = None
    for w in range(0, len(y) - window + 1):
        se, batches = batch_se(y[w:])
        se *= math.sqrt((len(y) - w) / window)
        if best is None or abs(se - r["mfr_se"]) < abs(best[0] - r["mfr_se"]):
            best = (se, batches)
    return r["mfr_se"] * t_allowance(best[1] - 1)


def rms(zs):
    return math.sqrt(sum(z * z for z in zs) / len(zs)) if zs else float("nan")


rows, all_z, all_zt, by_window = [], [], [], {"short": [], "long": []}
for speed, files in GROUPS:
    runs = [(os.path.basename(f)[:-5], json.load(open(f))) for f in files if os.path.exists(f)]
    if len(runs) < 3:
        print(f"\n{speed} m/s: {len(runs)} seeds recorded, too few to judge")
        continue
    m = [r["mfr"] for _, r in runs]
    s = [r["mfr_se"] for _, r in runs]
    cpu = [r["cpu_time"] for _, r in runs]
    n, mean, sd = len(m), statistics.fmean(m), statistics.stdev(m)
    print(f"\n{speed} m/s, {n} seeds: MFR {mean:.4f}, SD between seeds {sd:.4f}, mean reported SE "
          f"{statistics.fmean(s):.4f}, ratio {sd / statistics.fmean(s):.2f}; CPU {statistics.fmean(cpu):.0f} s a seed "
          f"({min(cpu):.0f}–{max(cpu):.0f})")
    long = long_run(speed)
    if not speed.endswith(" t"):
        sw = [widened_offline(r) for _, r in runs]
        zw = [(m[i] - statistics.fmean(m[:i] + m[i + 1:])) /
              math.sqrt(sw[i] ** 2 + statistics.variance(m[:i] + m[i + 1:]) / (n - 1)) for i in range(n)]
        print(f"  these runs' SEs widened by t as a result reports them now: RMS z {rms(zw):.2f}")
    zs, zls = [], []
    for i, (name, r) in enumerate(runs):
        others = m[:i] + m[i + 1:]
        z = (m[i] - statistics.fmean(others)) / math.sqrt(s[i] ** 2 + statistics.stdev(others) ** 2 / len(others))
        zs.append(z)
        st = r["steady_state"]
        # A window of at most 12 blocks: at or near the least window (8), from an SE of few blocks.
        if not speed.endswith(" t"):
            by_window["short" if st["window_blocks"] <= 12 else "long"].append(z)
        against = ""
        if long:
            zl = (m[i] - long[0]) / math.hypot(s[i], long[1])
            zls.append(zl)
            against = f"against the long run {zl:+.2f}  "
        print(f"  {name:8s} {m[i]:.4f} ± {s[i]:.4f}  z {z:+.2f}  {against}"
              f"window {st['window_blocks']:3d} blocks  CPU {r['cpu_time']:.0f} s  {st['stop']}")
    if not speed.endswith(" t"):
        all_z += zs
    else:
        all_zt.extend(zs)
    line = f"  RMS z {rms(zs):.2f}"
    long_cells = ["–", "–", "–"]
    if long:
        lm, lse, lblocks = long
        zmean = (mean - lm) / math.hypot(sd / math.sqrt(n), lse)
        within = sum(abs(z) <= 2 for z in zls)
        line += (f"; the long run's last half ({lblocks} blocks) {lm:.4f} ± {lse:.4f}: the seeds' mean "
                 f"{zmean:+.2f} combined SE from it, {within} of {n} seeds within 2 SE")
        long_cells = [f"{lm:.4f} ± {lse:.4f}", f"{zmean:+.1f}", f"{within}/{n}"]
    print(line)
    rows.append([speed, str(n), f"{mean:.4f}", f"{sd:.4f}", f"{statistics.fmean(s):.4f}",
                 f"{sd / statistics.fmean(s):.2f}", f"{rms(zs):.2f}", *long_cells, f"{statistics.fmean(cpu):.0f}"])

print("\n| v m/s | seeds | MFR (mean) | SD between seeds | mean reported SE | SD/SE | RMS z | long run, last half | seeds' mean from it (SE) | seeds within 2 SE of it | CPU s a seed |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for row in rows:
    print("| " + " | ".join(row) + " |")
if all_z:
    print(f"\nall speeds: RMS z {rms(all_z):.2f} over {len(all_z)} seeds; windows of at most 12 blocks "
          f"{rms(by_window['short']):.2f} ({len(by_window['short'])} seeds), longer {rms(by_window['long']):.2f} "
          f"({len(by_window['long'])} seeds)")
if all_zt:
    print(f"the seeds run with the SE widened by t: RMS z {rms(all_zt):.2f} over {len(all_zt)} seeds")
