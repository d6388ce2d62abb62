#!/usr/bin/env python3
"""A point's SE: from the window MSER chose, or from every block after the warm-up.

    python3 docs/study/point-cost/settled_se.py pairs RUN_A RUN_B   # two runs of the same points
    python3 docs/study/point-cost/settled_se.py mc                  # synthetic steady blocks
    python3 docs/study/point-cost/settled_se.py mc-t                # the same, SE widened by t

pairs: RUN_A and RUN_B are sweep directories of the same design with other particle seeds, or one
from rest and one warm-started (with the 0.6 floor of its warm-up) (each
with results.csv and runs/<hash>/result.json). For each point that flows in both, z = ΔMFR over
the combined SE, (1) as the runs reported it, and recomputed from each run's block series
(steady_state.block_mfr) after the warm-up (max(0.3 s · v, 10 D) of travel in blocks of 5 D):
(2) "window": mean and SE over the window MSER keeps (the estimator before); (3) "no MSER": mean
and SE over every block after the warm-up; (4) "settled": MSER's window for the mean, the SE from
every block after the warm-up scaled to the window's length (the estimator now). If the SE is
honest, z has an RMS of about 1 (a little above: each SE is estimated from ~9 blocks).

mc: stationary blocks (mean 1, coefficient of variation 0.12-0.17, lag-1 correlation 0 or -0.12
as measured), the deck's stop rule (least window 8 blocks, SE <= 5 % of the mean) with each
estimator; z = (mean - 1) / SE over 4,000 runs.

mc-t: the same blocks and the "settled" SE, the deck stopping on the plain SE (z rule, the deck
before; "z, least 16" with a least window of 16 blocks) or on the SE widened by Student's t for
its k - 1 degrees of freedom (t rule, the deck now); z from the plain SE and from the widened one
(what a result reports now); 1,500 runs each, CV 0.12-0.25.
"""
import csv, importlib.util, json, math, os, random, statistics, sys

# MSER truncation (White 1997) as the transient study computes it.
_spec = importlib.util.spec_from_file_location(
    "transient", os.path.join(os.path.dirname(__file__), "..", "recoater", "transient.py"))
_transient = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_transient)
mser = _transient.mser


def load(d):
    out = {}
    for r in csv.DictReader(open(os.path.join(d, "results.csv"))):
        f = os.path.join(d, "runs", r["hash"], "result.json")
        if r["status"] == "done" and os.path.exists(f):
            j = json.load(open(f))
            out[r["index"]] = j.get("measured") or j
    return out


def mean(y):
    return sum(y) / len(y)


def sd(y):
    m = mean(y)
    return math.sqrt(sum((v - m) ** 2 for v in y) / (len(y) - 1))


def estimate(y, kind):
    """(mean, SE) of a block series after the warm-up."""
    d = 0 if kind == "no MSER" else mser(y)
    w = y[d:]
    spread = sd(y) if kind == "settled" else sd(w)
    return mean(w), spread / math.sqrt(len(w))


def warmup_blocks(r):
    p = r["parameters"]
    d = p["diameter"] * 1e-3
    cold = math.ceil(max(0.3 * p["blade_speed"], 10 * d) / d / 5.0)
    if not r.get("warm_start"):
        return cold
    # A warm start's warm-up (src/scenes/conveyor/warm.rs): a share of the cold one, from 0.6
    # (LEAST_WARMUP_SHARE) up to all of it at a distance of 0.5 (FULL_WARMUP_DISTANCE).
    share = min(max(r["warm_start"]["distance"] / 0.5, 0.6), 1.0)
    return math.ceil(cold * share)


def pairs(a_dir, b_dir):
    a, b = load(a_dir), load(b_dir)
    both = [i for i in a if i in b and a[i]["mfr"] >= 0.01 and b[i]["mfr"] >= 0.01]
    print(f"{len(both)} points flow in both runs\n")
    print("| SE | RMS z | beyond 2 SE | beyond 3 SE |\n|---|---|---|---|")
    for kind in ("reported", "window", "no MSER", "settled"):
        zs = []
        for i in both:
            if kind == "reported":
                (ma, sa), (mb, sb) = (a[i]["mfr"], a[i]["mfr_se"]), (b[i]["mfr"], b[i]["mfr_se"])
            else:
                ya = a[i]["steady_state"]["block_mfr"][warmup_blocks(a[i]):]
                yb = b[i]["steady_state"]["block_mfr"][warmup_blocks(b[i]):]
                (ma, sa), (mb, sb) = estimate(ya, kind), estimate(yb, kind)
            zs.append((mb - ma) / math.hypot(sa, sb))
        rms = math.sqrt(mean([z * z for z in zs]))
        print(f"| {kind} | {rms:.2f} | {sum(abs(z) > 2 for z in zs)} | {sum(abs(z) > 3 for z in zs)} |")


def mc():
    rng = random.Random(2)
    print("| block CV | lag-1 ACF | SE | blocks | RMS z | beyond 3 SE |\n|---|---|---|---|---|---|")
    for rho in (0.0, -0.12):
        theta = 0.0 if rho == 0 else (1 - math.sqrt(1 - 4 * rho * rho)) / (2 * rho)
        for cv in (0.12, 0.17):
            for kind in ("window", "no MSER", "settled"):
                zs, ks = [], []
                for _ in range(4000):
                    e = [rng.gauss(0, 1) for _ in range(301)]
                    y = [1 + cv * (e[k + 1] + theta * e[k]) / math.sqrt(1 + theta * theta) for k in range(300)]
                    for k in range(8, 301):
                        d = 0 if kind == "no MSER" else mser(y[:k])
                        if d >= k // 2:
                            continue
                        m, se = estimate(y[:k], kind)
                        if se <= 0.05 * m:
                            zs.append((m - 1) / se)
                            ks.append(k)
                            break
                rms = math.sqrt(mean([z * z for z in zs]))
                print(f"| {cv} | {rho:+.2f} | {kind} | {mean(ks):.1f} | {rms:.2f} | {100 * mean([abs(z) > 3 for z in zs]):.1f} % |")


def t_allowance(dof):
    """t_0.975(dof) / 1.96 by three terms of its Cornish-Fisher series (src/measure/steady.rs)."""
    u = 1.0 / dof
    return 1 + u * (1.21037 + u * (1.4401 + u * 1.3041))


def mc_t():
    rng = random.Random(3)
    print("| block CV | lag-1 ACF | stop rule | blocks | RMS z, plain SE | RMS z, widened SE | beyond 3 widened SE |")
    print("|---|---|---|---|---|---|---|")
    for rho in (0.0, -0.12):
        theta = 0.0 if rho == 0 else (1 - math.sqrt(1 - 4 * rho * rho)) / (2 * rho)
        for cv in (0.12, 0.17, 0.25):
            for rule in ("z", "t", "z, least 16"):
                least = 16 if rule == "z, least 16" else 8
                plain, widened, ks = [], [], []
                for _ in range(1500):
                    e = [rng.gauss(0, 1) for _ in range(401)]
                    y = [1 + cv * (e[k + 1] + theta * e[k]) / math.sqrt(1 + theta * theta) for k in range(400)]
                    for k in range(least, 401):
                        if mser(y[:k]) >= k // 2:
                            continue
                        m, se = estimate(y[:k], "settled")
                        a = t_allowance(k - 1)
                        if se * (a if rule == "t" else 1.0) <= 0.05 * m:
                            plain.append((m - 1) / se)
                            widened.append((m - 1) / (se * a))
                            ks.append(k)
                            break
                rms = lambda zs: math.sqrt(mean([z * z for z in zs]))
                print(f"| {cv} | {rho:+.2f} | {rule} | {mean(ks):.1f} | {rms(plain):.2f} | {rms(widened):.2f} | "
                      f"{100 * mean([abs(z) > 3 for z in widened]):.1f} % |", flush=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["pairs"] and len(sys.argv) == 4:
        pairs(sys.argv[2], sys.argv[3])
    elif sys.argv[1:] == ["mc"]:
        mc()
    elif sys.argv[1:] == ["mc-t"]:
        mc_t()
    else:
        sys.exit(__doc__)
