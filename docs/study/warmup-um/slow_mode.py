# How long the real powder's slow state lasts at 0.063 m/s (docs/study/warmup-um.md "The slow
# mode at 0.063 m/s"): two seeds of the point of sweeps/ti64-machine.toml at blade_speed 0.063,
# seed 4 (the one whose ten-seed window sat at 0.110 against 0.083-0.099) and seed 1, each run
# for a 2,000 D window that no target stops (docs/study/steady/seeds/ti64-v0.063-long/, the
# command in its README). For each: the MFR of the window's quarters, the batch-means SE of the
# window at batch lengths 1-64 blocks (it grows until the batches outlast the correlation, then
# levels), the integrated autocorrelation time of the blocks, and the mean of each 40-block
# stretch (the length of a default window here) against the ten default seeds' spread.
#   python3 docs/study/warmup-um/slow_mode.py
import json, math, os, statistics

here = os.path.dirname(os.path.abspath(__file__))
long_dir = os.path.join(here, "..", "steady", "seeds", "ti64-v0.063-long")
short_dir = os.path.join(here, "..", "steady", "seeds", "ti64-v0.063-t")


def batch_se(y, b):
    k = len(y) // b
    if k < 4:
        return None
    means = [statistics.fmean(y[i * b:(i + 1) * b]) for i in range(k)]
    return statistics.stdev(means) / math.sqrt(k)


def tau_int(y, window=None):
    """Integrated autocorrelation time, 1 + 2 sum of rho_k, summed until rho first falls
    below zero (Geyer's initial positive sequence, in its simplest form)."""
    n, m = len(y), statistics.fmean(y)
    var = sum((v - m) ** 2 for v in y) / n
    t = 1.0
    for k in range(1, (window or n // 4)):
        r = sum((y[i] - m) * (y[i + k] - m) for i in range(n - k)) / (n * var)
        if r <= 0:
            break
        t += 2 * r
    return t


shorts = []
for k in range(1, 11):
    f = os.path.join(short_dir, f"seed-{k}.json")
    if os.path.exists(f):
        shorts.append(json.load(open(f))["mfr"])
print(f"ten default seeds (0.063 t): mean {statistics.fmean(shorts):.4f}, SD {statistics.stdev(shorts):.4f}, "
      f"range {min(shorts):.4f}-{max(shorts):.4f}")
for seed in (4, 1):
    f = os.path.join(long_dir, f"seed-{seed}.json")
    failed = os.path.join(long_dir, f"seed-{seed}-failure.json")
    if os.path.exists(failed):
        # Refused by the steadiness check over its window: what it measured is kept.
        fail = json.load(open(failed))
        print(f"\nseed {seed}: failed ({fail['class']}: {fail['reason']})")
        r = fail["measured"]
    elif os.path.exists(f):
        r = json.load(open(f))
    else:
        print(f"seed {seed}: not run yet")
        continue
    ss = r["steady_state"]
    y = ss["block_mfr"][ss["transient_blocks"]:]
    y = y[: ss["window_blocks"]] if ss["window_blocks"] else y
    print(f"seed {seed}: MFR {r.get('mfr', float('nan')):.4f} ± {r.get('mfr_se') or float('nan'):.4f} over {len(y)} blocks "
          f"({len(y) * ss['block_diameters']:.0f} D), stop {ss['stop']}, CPU {r.get('cpu_time', 0):.0f} s")
    q = len(y) // 4
    print("  quarters:", ", ".join(f"{statistics.fmean(y[i * q:(i + 1) * q]):.4f}" for i in range(4)))
    print("  batch-means SE by batch length (blocks):",
          ", ".join(f"{b}: {batch_se(y, b):.4f}" for b in (1, 2, 4, 8, 16, 32, 64) if batch_se(y, b)))
    print(f"  integrated autocorrelation time: {tau_int(y):.1f} blocks; "
          f"SD of one block {statistics.stdev(y):.4f}")
    w = 40
    stretches = [statistics.fmean(y[i:i + w]) for i in range(0, len(y) - w + 1, w)]
    print(f"  means of {w}-block stretches: " + ", ".join(f"{s:.4f}" for s in stretches)
          + f"  (SD {statistics.stdev(stretches):.4f})" if len(stretches) > 1 else "")
