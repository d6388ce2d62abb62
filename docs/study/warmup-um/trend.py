# The conveyor's steadiness test over every recorded window of the studies, judged both ways:
# single blocks with |z| > 3 (the test until it changed) and the batch means of
# src/measure/steady.rs `window_trend` (batches doubled while what the fitted line leaves has a
# positive lag-1 autocorrelation and at least 8 batches remain; Student's quantile for the
# batches' degrees of freedom at 0.27 %). Prints how many windows were read, and each whose
# verdict differs. Needs scipy (the t quantile).
#   python3 docs/study/warmup-um/trend.py
import glob, json, os

from scipy import stats

here = os.path.dirname(os.path.abspath(__file__))
FALSE_ALARM = 0.0027


def mean(y):
    return sum(y) / len(y)


def acf1(y):
    m = mean(y)
    var = sum((v - m) ** 2 for v in y)
    return sum((a - m) * (b - m) for a, b in zip(y, y[1:])) / var if var > 0 else 0.0


def line(y):
    n = len(y)
    xm, ym = (n - 1) / 2, mean(y)
    sxx = sum((i - xm) ** 2 for i in range(n))
    slope = sum((i - xm) * (v - ym) for i, v in enumerate(y)) / sxx
    return slope, sxx, [v - ym - slope * (i - xm) for i, v in enumerate(y)]


def trend_z(y):
    if len(y) < 3:
        return 0.0
    slope, sxx, r = line(y)
    se = (sum(v * v for v in r) / (len(y) - 2) / sxx) ** 0.5
    return slope / se if se > 0 else 0.0


def batch_size(y):
    b = 1
    while True:
        means = [mean(y[i:i + b]) for i in range(0, len(y) - len(y) % b, b)]
        if acf1(means) <= 0 or len(y) // (2 * b) < 8:
            return b
        b *= 2


def batched(w):
    b = batch_size(line(w)[2])
    w = w[len(w) % b:]
    means = [mean(w[i:i + b]) for i in range(0, len(w), b)]
    limit = stats.t.ppf(1 - FALSE_ALARM / 2, len(means) - 2) if len(means) > 2 else float("inf")
    return trend_z(means), limit


read, changed = 0, []
for path in sorted(glob.glob(os.path.join(here, "..", "**", "*.json"), recursive=True)):
    try:
        record = json.load(open(path))
    except (ValueError, OSError):
        continue
    if not isinstance(record, dict):
        continue
    measured = record.get("measured") if isinstance(record.get("measured"), dict) else record
    state = measured.get("steady_state") if isinstance(measured, dict) else None
    if not isinstance(state, dict) or "block_mfr" not in state:
        continue
    w = state["block_mfr"][state["transient_blocks"]:]
    if len(w) < 3:
        continue
    read += 1
    z, limit = batched(w)
    if (abs(trend_z(w)) > 3) != (abs(z) > limit):
        changed.append((os.path.relpath(path, os.path.join(here, "..")), len(w), trend_z(w), z, limit))
print(f"{read} recorded windows; {len(changed)} verdicts differ")
for p, n, old, z, limit in changed:
    print(f"  {p}: {n} blocks, single blocks {old:+.2f} (limit 3), batch means {z:+.2f} (limit {limit:.2f})")
