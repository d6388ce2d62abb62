# Each layers record judged again by the current steady rule (src/scenes/layers/measure.rs,
# restated here): MSER's cut of the laid passes (a fused bed: its packing's and its depth's, the
# later), the mean and SE of what is left widened for the lag-1 autocorrelation the rule allows
# for (a fused bed's depth 0.65, its packing 0.15; a loose bed none), and the slope test at
# 2.5 % a series (fused) or 5 % (loose) widened likewise. Also: the pooled lag-1
# autocorrelation of the steady records' passes the allowance comes from.
# With --passes N, each record is judged on its first N passes only (what a shorter run would
# have answered).
#   /usr/bin/python3 docs/study/layers/rejudge.py [--passes N] docs/study/layers/record/*.json
import json, sys, os
import numpy as np
from scipy import stats

LAG1 = {"fused": (0.15, 0.65), "loose": (0.0, 0.0)}


def mser(y):
    n = len(y)
    best = min(range(n // 2 + 1), key=lambda d: (np.var(y[d:]) * len(y[d:])) / len(y[d:]) ** 2)
    return best


def factor(n, rho, slope):
    p = 2 if slope else 1
    if n <= p or rho == 0:
        return 1.0
    i = np.arange(n)
    S = rho ** np.abs(i[:, None] - i[None, :])
    t = i - (n - 1) / 2
    sxx = (t * t).sum()
    w = t / sxx if slope else np.ones(n) / n
    taken = S.sum() / n + (t @ S @ t / sxx if slope else 0)
    return np.sqrt((w @ S @ w) / ((n - taken) / (n - p) * (w @ w)))


def trend_z(y):
    n = len(y)
    t = np.arange(n) - (n - 1) / 2
    sxx = (t * t).sum()
    s = ((y - y.mean()) * t).sum() / sxx
    rss = ((y - y.mean() - s * t) ** 2).sum()
    se = np.sqrt(rss / (n - 2) / sxx)
    return s / se if se > 0 else 0.0


def layers_of(path):
    try:
        d = json.load(open(path))
    except (OSError, ValueError):
        return None
    return d.get("measured", d).get("layers") if isinstance(d, dict) else None


def r1(y):
    d = y - y.mean()
    return (d[1:] * d[:-1]).sum() / (d * d).sum()


def main():
    args = sys.argv[1:]
    keep = None
    if args[:1] == ["--passes"]:
        keep, args = int(args[1]), args[2:]
    rows, pooled = [], {"packing": [], "depth": []}
    for f in args:
        L = layers_of(f)
        if not L:
            continue
        fused = L["bed"] == "fused"
        P = L["passes"][:keep] if keep else L["passes"]
        first = sum(1 for p in P if p.get("search"))
        ans = np.array([p["packing"] if fused else p["relative_density"] for p in P])
        dep = np.array([p["effective_thickness_m"] * 1e6 for p in P])
        cut = first + (max(mser(ans[first:]), mser(dep[first:])) if fused else mser(ans[first:]))
        n = len(P) - cut
        a_lag, d_lag = LAG1[L["bed"]]
        series = 2 if fused else 1
        lim = lambda rho: stats.t.ppf(1 - 0.05 / series / 2, n - 2) * factor(n, rho, True) if n >= 3 else np.inf
        za, zd = trend_z(ans[cut:]), trend_z(dep[cut:])
        steady = n >= 3 and abs(za) <= lim(a_lag) and (not fused or abs(zd) <= lim(d_lag))
        independent = n >= 3 and abs(za) <= lim(0) and (not fused or abs(zd) <= lim(0))
        se = lambda y, rho: y.std(ddof=1) / np.sqrt(len(y)) * factor(len(y), rho, False)
        pack = np.array([p["packing"] for p in P])[cut:]
        rows.append((os.path.basename(f)[:-5], L["bed"], cut + 1, L["steady"], independent, steady,
                     pack.mean(), se(pack, a_lag), dep[cut:].mean(), se(dep[cut:], d_lag), za, lim(a_lag), zd, lim(d_lag)))
        if fused and L["steady"] and len(P) >= 14:
            pooled["packing"].append(r1(np.array([p["packing"] for p in P][6:14])))
            pooled["depth"].append(r1(dep[6:14]))

    print("| record | bed | steady from | steady: as run | read as independent | the current rule | packing | depth, µm | packing slope / limit | depth slope / limit |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        name, bed, frm, was, ind, now, pm, ps, dm, ds, za, la, zd, ld = r
        dz = f"{abs(zd):.1f} / {ld:.1f}" if bed == "fused" else "—"
        print(f"| {name} | {bed} | {frm} | {'yes' if was else 'no'} | {'yes' if ind else 'no'} | {'yes' if now else 'no'} | {pm:.3f} ± {ps:.3f} | {dm:.1f} ± {ds:.1f} | {abs(za):.1f} / {la:.1f} | {dz} |")

    # Pooled lag-1 autocorrelation of the steady fused records' passes 7-14, and the AR(1)
    # correlation whose eight-pass estimate has that mean (a short series' estimate is biased low).
    rng = np.random.default_rng(2)


    def expected_r1(rho, n=8, N=40000):
        x = rng.standard_normal(N) / np.sqrt(1 - rho * rho)
        Y = np.empty((N, n + 20))
        for i in range(n + 20):
            x = rho * x + rng.standard_normal(N)
            Y[:, i] = x
        D = Y[:, -n:] - Y[:, -n:].mean(1, keepdims=True)
        return ((D[:, 1:] * D[:, :-1]).sum(1) / (D * D).sum(1)).mean()


    grid = {round(r, 2): expected_r1(r) for r in np.arange(0, 0.96, 0.05)}
    inv = lambda m: min(grid, key=lambda r: abs(grid[r] - m))
    print()
    for k, v in pooled.items():
        v = np.array(v)
        m, s = v.mean(), v.std(ddof=1) / np.sqrt(len(v))
        print(f"{k}: {len(v)} steady fused records, mean lag-1 r over passes 7-14 {m:+.2f} ± {s:.2f}"
              f" -> AR(1) rho {inv(m):.2f} ({inv(m - s):.2f}-{inv(m + s):.2f})")


if __name__ == "__main__":
    main()
