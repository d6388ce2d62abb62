#!/usr/bin/env python3
"""The nine-point machine lattice (machine-lattice.sh) as a table, and beside an earlier lattice:
each point's steady layer, its passes and CPU, and each value's move over the combined SE
sqrt(SE1² + SE2²) (the cover's SE is its steady passes' SD/√n: a result gives its mean only).

    python3 docs/study/layers/lattice.py machine-lattice-laid [machine-lattice]
"""
import json, math, os, sys, glob

HERE = os.path.dirname(os.path.abspath(__file__))


def points(tag):
    """(layer µm, speed m/s) -> result.json of every finished point under record/<tag>/."""
    out = {}
    for f in glob.glob(os.path.join(HERE, "record", tag, "*", "result.json")):
        r = json.load(open(f))
        p = r["parameters"]
        out[(round(p["layer_thickness"] * 1e3), round(p["blade_speed"], 3))] = r
    return out


def steady(r):
    l = r["layers"]
    kept = [p for p in l["passes"] if p["k"] >= l["steady_from"]]
    cov = [p["covered_fraction"] for p in kept]
    n = len(cov)
    m = sum(cov) / n
    sd = math.sqrt(sum((c - m) ** 2 for c in cov) / (n - 1)) if n > 1 else float("nan")
    return {
        "packing": (l["packing"], l["packing_se"]),
        "depth": (l["effective_thickness_m"] * 1e6, l["effective_thickness_se_m"] * 1e6),
        "cover": (m, sd / math.sqrt(n)),
        "roughness": l["roughness_d"],
        "from": l["steady_from"],
        "passes": len(l["passes"]),
        "cpu": r["cpu_time"],
    }


def main():
    new = points(sys.argv[1])
    old = points(sys.argv[2]) if len(sys.argv) > 2 else {}
    print("| layer (µm) | speed (m/s) | packing ± SE | depth under the tip (µm) | cover ± SE | roughness (D) | steady from / passes | CPU s |"
          + (" Δ / SE against the earlier lattice (packing, depth) |" if old else ""))
    print("|---|---|---|---|---|---|---|---|" + ("---|" if old else ""))
    total = 0.0
    for key in sorted(new):
        s = steady(new[key])
        total += s["cpu"]
        row = (f"| {key[0]} | {key[1]:g} | {s['packing'][0]:.3f} ± {s['packing'][1]:.3f} | "
               f"{s['depth'][0]:.1f} ± {s['depth'][1]:.1f} | {s['cover'][0]:.2f} ± {s['cover'][1]:.2f} | "
               f"{s['roughness']:.2f} | {s['from']} / {s['passes']} | {s['cpu']:.0f} |")
        if old:
            if key in old:
                o = steady(old[key])
                moves = []
                for q in ("packing", "depth"):
                    (a, sa), (b, sb) = s[q], o[q]
                    moves.append(f"{(a - b) / math.hypot(sa, sb):+.1f}")
                row += " " + ", ".join(moves) + " |"
            else:
                row += " — |"
        print(row)
    print(f"\n{len(new)} points, {total:,.0f} CPU s"
          + (f"; the earlier lattice's same points {sum(steady(old[k])['cpu'] for k in new if k in old):,.0f} CPU s" if old else ""))


if __name__ == "__main__":
    main()
