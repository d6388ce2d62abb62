#!/usr/bin/env python3
"""The cuts of "A pass is its crossing" (docs/study/layers.md), from record/cuts/ (cuts.sh):
per scene, each run's CPU per pass and steps, and its steady layer beside the run it is cut from
(its reference): each value's difference over the combined SE sqrt(SE1² + SE2²). The covered
fraction's SE is its steady passes' SD/√n (the result gives the mean only).

    python3 docs/study/layers/cuts.py base:A A:AC       # reference:cut pairs
"""
import json, math, os, re, sys, glob

HERE = os.path.dirname(os.path.abspath(__file__))
REC = os.path.join(HERE, "record", "cuts")


def load(name):
    p = os.path.join(REC, name + ".json")
    if not os.path.exists(p):
        return None
    return json.load(open(p))


def passes(name):
    out = {}
    for f in glob.glob(os.path.join(REC, name, "pass.*.json")):
        d = json.load(open(f))
        out[d["k"]] = d
    return [out[k] for k in sorted(out)]


def mean_sd(xs):
    n = len(xs)
    m = sum(xs) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1)) if n > 1 else float("nan")
    return m, sd


def steady(r):
    l = r["layers"]
    kept = [p for p in l["passes"] if p["k"] >= l["steady_from"]]
    cov = [p["covered_fraction"] for p in kept]
    m, sd = mean_sd(cov)
    return {
        "relative density": (l["relative_density"], l["relative_density_se"]),
        "packing": (l["packing"], l["packing_se"]),
        "depth µm": (l["effective_thickness_m"] * 1e6, l["effective_thickness_se_m"] * 1e6),
        "cover": (m, sd / math.sqrt(len(cov))),
    }, l


def cost(name):
    """CPU s of each pass, in order."""
    return [p["cpu_time"] for p in passes(name) if p.get("cpu_time")]


def row(name):
    r = load(name)
    cpu = cost(name)
    s = f"{name}: {len(cpu)} passes, CPU {sum(cpu):.0f} s, {sum(cpu)/max(len(cpu),1):.1f} s a pass"
    if r is None:
        return s + " (no result yet)", None, cpu
    st, l = steady(r)
    s += f", {r.get('steps', 0):,} steps; steady {l['steady']} from pass {l['steady_from']} of {len(l['passes'])}"
    return s, st, cpu


def main():
    for pair in sys.argv[1:]:
        ref, cut = pair.split(":")
        for scene in ["machine", "PS1"]:
            a, b = f"{ref}-{scene}", f"{cut}-{scene}"
            ra, sa, ca = row(a)
            rb, sb, cb = row(b)
            print(f"## {cut} against {ref}, {scene}")
            print("  " + ra)
            print("  " + rb)
            if ca and cb:
                ma, mb = sum(ca) / len(ca), sum(cb) / len(cb)
                # A loose bed's later passes cost more: the ratio over the passes both ran too.
                n = min(len(ca), len(cb))
                sa_, sb_ = sum(ca[:n]), sum(cb[:n])
                print(f"  CPU a pass {ma:.1f} → {mb:.1f} s: ratio {ma / mb:.2f}; over passes 1–{n}: {sa_ / n:.1f} → {sb_ / n:.1f} s, ratio {sa_ / sb_:.2f}")
            if sa and sb:
                for k in sa:
                    (x, ex), (y, ey) = sa[k], sb[k]
                    c = math.hypot(ex, ey)
                    z = (y - x) / c if c > 0 else float("inf")
                    print(f"  {k:17s} {x:8.3f} ± {ex:.3f}  →  {y:8.3f} ± {ey:.3f}   Δ/SE {z:+.2f}")
            print()


if __name__ == "__main__":
    main()
