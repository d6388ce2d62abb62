# The SE a run reports, recomputed from its recorded blocks under another batching bound: the
# lag-1 autocorrelation of the batch means up to which batches of one block are kept
# (src/measure/steady.rs MAX_BATCH_ACF, 0.2 today). The deck's stop rule does not read it, so
# each run would stop where it did and only its reported SE changes: recomputed here exactly as
# settled_se does (batch means over every block after the warm-up, scaled to the window, widened
# by Student's t for the batches less one). The bound a run was recorded with must give back its
# recorded SE: 0.2 for the runs recorded since the SE was widened by t (labels "-t"), 0 for the
# fresh seeds recorded under the bound 0 (labels "-b0"); the older seeds' rows give their SE as
# a result reported it after the t widening.
# For each ten- or thirty-seed point: the SD between seeds, the mean SE and the RMS z.
#   python3 docs/study/warmup-um/batching.py
import glob, json, math, os, statistics

here = os.path.dirname(os.path.abspath(__file__))
steady = os.path.join(here, "..", "steady", "seeds")
POINTS = ["ti64-v0.2-t", "ti64-v0.08-t", "ti64-v0.063-t", "ti64-v0.063-b0",
          "f0.1-D1.0-g3.0-v1.5", "f0.2-D2.0-g4.2-v1.3", "f0.3-D3.0-g4.5-v1.2"]
BOUNDS = [0.2, 0.1, 0.0]


def t_allowance(dof):
    u = 1.0 / max(dof, 1.0)
    return 1 + u * (1.21037 + u * (1.4401 + u * 1.3041))


def acf1(y):
    if len(y) < 3:
        return 0.0
    m = statistics.fmean(y)
    var = sum((v - m) ** 2 for v in y)
    return sum((y[i] - m) * (y[i + 1] - m) for i in range(len(y) - 1)) / var if var > 0 else 0.0


def batch_means_se(y, bound):
    b = 1
    while True:
        means = [statistics.fmean(y[i:i + b]) for i in range(0, len(y) - b + 1, b)]
        if acf1(means) <= bound or len(y) // (2 * b) < 8:
            n = len(means)
            m = statistics.fmean(means)
            var = sum((v - m) ** 2 for v in means) / max(n - 1, 1)
            return math.sqrt(var / n), n
        b *= 2


def settled_se(y, d0, window, bound):
    se, batches = batch_means_se(y[d0:], bound)
    return se * math.sqrt((len(y) - d0) / window) * t_allowance(batches - 1)


def rms(z):
    return math.sqrt(sum(v * v for v in z) / len(z))


for label in POINTS:
    runs = [json.load(open(f)) for f in sorted(glob.glob(os.path.join(steady, label, "seed-*.json")))]
    runs = [r for r in runs if r.get("steady_state")]
    if len(runs) < 3:
        print(f"{label}: {len(runs)} seeds recorded, too few")
        continue
    m = [r["mfr"] for r in runs]
    n = len(m)
    # The warm-up: the least transient among the seeds (MSER only ever extends it).
    d0 = min(r["steady_state"]["transient_blocks"] for r in runs)
    cells = []
    for bound in BOUNDS:
        se = []
        for r in runs:
            st = r["steady_state"]
            y = st["block_mfr"]
            s = settled_se(y, d0, st["window_blocks"], bound)
            recorded_with = {"-t": 0.2, "b0": 0.0}.get(label[-2:])
            if bound == recorded_with and abs(s - r["mfr_se"]) > 1e-9 * max(s, 1e-12) + 1e-12:
                s_note = f"{r['mfr_se']:.6f} recorded, {s:.6f} recomputed"
                raise SystemExit(f"{label}: the bound {bound} does not give back the recorded SE ({s_note})")
            se.append(s)
        z = [(m[i] - statistics.fmean(m[:i] + m[i + 1:])) /
             math.sqrt(se[i] ** 2 + statistics.variance(m[:i] + m[i + 1:]) / (n - 1)) for i in range(n)]
        cells.append(f"bound {bound}: SE {statistics.fmean(se):.4f}, SD/SE {statistics.stdev(m) / statistics.fmean(se):.2f}, RMS z {rms(z):.2f}")
    print(f"{label} ({n} seeds, warm-up {d0} blocks, SD {statistics.stdev(m):.4f}): " + "; ".join(cells))

# The 0.063 m/s point's twenty seeds under the bound 0: seeds 1-10 (recorded under 0.2, their SE
# recomputed) and the fresh seeds 11-20 (recorded under 0).
pooled, pooled_se = [], []
for label in ("ti64-v0.063-t", "ti64-v0.063-b0"):
    runs = [json.load(open(f)) for f in sorted(glob.glob(os.path.join(steady, label, "seed-*.json")))]
    runs = [r for r in runs if r.get("steady_state")]
    if not runs:
        continue
    d0 = min(r["steady_state"]["transient_blocks"] for r in runs)
    for r in runs:
        st = r["steady_state"]
        pooled.append(r["mfr"])
        pooled_se.append(settled_se(st["block_mfr"], d0, st["window_blocks"], 0.0))
n = len(pooled)
if n >= 3:
    z = [(pooled[i] - statistics.fmean(pooled[:i] + pooled[i + 1:])) /
         math.sqrt(pooled_se[i] ** 2 + statistics.variance(pooled[:i] + pooled[i + 1:]) / (n - 1)) for i in range(n)]
    print(f"ti64 0.063 m/s, all {n} seeds under the bound 0: MFR {statistics.fmean(pooled):.4f}, SD {statistics.stdev(pooled):.4f}, "
          f"mean SE {statistics.fmean(pooled_se):.4f}, SD/SE {statistics.stdev(pooled) / statistics.fmean(pooled_se):.2f}, RMS z {rms(z):.2f}")
