# A point that stops once its steady layer holds, replayed on the recorded runs: each record's
# passes judged after every pass from the least on by the rule src/scenes/layers/measure.rs
# applies (the steady rule of rejudge.py, and short of the most passes at least KEPT passes left
# after MSER's cut and, on a fused bed, a mean relative density within Student's 5 % of the
# whole drop), the pass it would have stopped at, and its answer there against the answer
# of all its passes (the difference over the two SEs combined, as if independent: the two share
# passes, so this overstates how well they agree by at most √2).
#   /usr/bin/python3 docs/study/layers/stop_rule.py [--kept N] docs/study/layers/record/*.json
import json, os, sys
import numpy as np
from scipy import stats

from rejudge import LAG1, factor, layers_of, mser, trend_z


def judge(P, bed):
    """(steady, kept passes, answer, its SE, depth) of passes P by the current rule."""
    fused = bed == "fused"
    first = sum(1 for p in P if p.get("search"))
    ans = np.array([p["packing"] if fused else p["relative_density"] for p in P])
    dep = np.array([p["effective_thickness_m"] * 1e6 for p in P])
    if len(P) - first < 1:
        return False, 0, np.nan, np.nan, np.nan, False
    cut = first + (max(mser(ans[first:]), mser(dep[first:])) if fused else mser(ans[first:]))
    n = len(P) - cut
    a_lag, d_lag = LAG1[bed]
    series = 2 if fused else 1
    lim = lambda rho: stats.t.ppf(1 - 0.05 / series / 2, n - 2) * factor(n, rho, True) if n >= 3 else np.inf
    steady = n >= 3 and abs(trend_z(ans[cut:])) <= lim(a_lag) and (
        not fused or abs(trend_z(dep[cut:])) <= lim(d_lag))
    se = ans[cut:].std(ddof=1) / np.sqrt(n) * factor(n, a_lag, False) if n >= 2 else np.nan
    if fused and n >= 2:
        # A steady fused bed keeps the whole drop: its relative density is 1 within its SE.
        rd = np.array([p["relative_density"] for p in P])[cut:]
        rd_se = rd.std(ddof=1) / np.sqrt(n) * factor(n, a_lag, False)
        keeps = abs(1 - rd.mean()) <= stats.t.ppf(1 - 0.05 / 2, n - 1) * rd_se
    else:
        keeps = True
    return steady, n, ans[cut:].mean(), se, dep[cut:].mean(), keeps


args = sys.argv[1:]
KEPT = 5
if args[:1] == ["--kept"]:
    KEPT, args = int(args[1]), args[2:]
print(f"| record | bed | passes | search | stops at | answer there | all passes | z | passes saved |")
print("|---|---|---:|---:|---:|---|---|---:|---:|")
saved, zs, stopped = [], [], 0
for f in args:
    L = layers_of(f)
    if not L:
        continue
    P, bed = L["passes"], L["bed"]
    search = sum(1 for p in P if p.get("search"))
    full = judge(P, bed)
    stop = None
    for k in range(search + KEPT, len(P)):
        st, n, a, se, _, keeps = judge(P[:k], bed)
        if st and n >= KEPT and keeps:
            stop = (k, a, se)
            break
    name = os.path.basename(f)[:-5]
    verdict = "steady" if full[0] else "not steady"
    if stop is None:
        print(f"| {name} | {bed} | {len(P)} | {search} | — (all {len(P)}) | — | {full[2]:.3f} ± {full[3]:.3f} ({verdict}) | — | 0 |")
        saved.append(0)
        continue
    k, a, se = stop
    z = (a - full[2]) / np.hypot(se, full[3])
    stopped += 1
    zs.append(z)
    saved.append((len(P) - k) / len(P))
    print(f"| {name} | {bed} | {len(P)} | {search} | {k} | {a:.3f} ± {se:.3f} | {full[2]:.3f} ± {full[3]:.3f} ({verdict}) | {z:+.2f} | {len(P) - k} |")
zs = np.array(zs)
print()
print(f"kept at least {KEPT}: {stopped} of {len(saved)} records stop early; passes saved {np.mean(saved):.0%} on average;"
      f" |z| at most {np.abs(zs).max():.2f}, RMS {np.sqrt((zs ** 2).mean()):.2f}, {np.sum(np.abs(zs) > 2)} beyond 2")
