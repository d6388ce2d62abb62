#!/usr/bin/env python3
"""The machine point's plate length (docs/study/layers.md "The plate's length, bounded"): the
steady layer of sweeps/ti64-layers.toml at 50 µm and 0.1 m/s on plates of 40, 80 and 160 mean
diameters, run on one deck with one binary (cuts.sh's `now` runs: record/cuts/now-machine*.json),
each against the longest, and the earlier deck's records of 20, 40 and 80 D (record/ti64-50um-0.1-gap*.json)
beside them. Draws plate_length.png; prints the Markdown table.

    python3 docs/study/layers/plate_length.py
"""
import json, math, os, sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cuts  # noqa: E402  steady(): a record's steady layer with its SEs

NOW = [(40, "now-machine"), (80, "now-machine-plate80"), (160, "now-machine-plate160")]
EARLIER = [(20, "ti64-50um-0.1-gap-plate20"), (40, "ti64-50um-0.1-gap"), (40, "ti64-50um-0.1-gap-seed2"),
           (80, "ti64-50um-0.1-gap-plate80"), (80, "ti64-50um-0.1-gap-plate80-seed2")]
MEASURES = ["packing", "depth µm", "cover"]


def earlier(label):
    p = os.path.join(HERE, "record", label + ".json")
    if not os.path.exists(p):
        return None
    r = json.load(open(p))
    r = r.get("measured") or r
    return cuts.steady(r)[0] if r.get("layers") else None


def main():
    now = [(d, name, cuts.load(name)) for d, name in NOW]
    now = [(d, name, cuts.steady(r)[0], sum(cuts.cost(name))) for d, name, r in now if r]
    print("| plate | steady from / passes | packing | powder under the tip (µm) | covered | CPU s |")
    print("|---|---|---|---|---|---|")
    for d, name, s, cpu in now:
        l = cuts.load(name)["layers"]
        cells = " | ".join(f"{s[k][0]:.3f} ± {s[k][1]:.3f}" if k != "depth µm" else f"{s[k][0]:.1f} ± {s[k][1]:.1f}"
                          for k in MEASURES)
        print(f"| {d} D | {l['steady_from']} / {len(l['passes'])} | {cells} | {cpu:,.0f} |")
    if len(now) > 1:
        d0, _, s0, _ = now[-1]
        print(f"\nEach against the longest ({d0} D): difference (combined SE)\n")
        print("| plate | " + " | ".join(MEASURES) + " |")
        print("|---|" + "---|" * len(MEASURES))
        for d, _, s, _ in now[:-1]:
            cells = []
            for k in MEASURES:
                (x, ex), (y, ey) = s[k], s0[k]
                c = math.hypot(ex, ey)
                cells.append(f"{x - y:+.3f} ({(x - y) / c:+.1f})" if k != "depth µm" else f"{x - y:+.1f} ({(x - y) / c:+.1f})")
            print(f"| {d} D | " + " | ".join(cells) + " |")
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.8))
    for ax, k in zip(axes, MEASURES):
        for d, label in EARLIER:
            s = earlier(label)
            if s:
                ax.errorbar([d * 1.04], [s[k][0]], yerr=[s[k][1]], color="0.6", marker="o", markerfacecolor="white",
                            linestyle="none", capsize=3)
        if now:
            ax.errorbar([d for d, *_ in now], [s[k][0] for _, _, s, _ in now], yerr=[s[k][1] for _, _, s, _ in now],
                        color="#3182bd", marker="o", capsize=3, label="today's deck, one run each")
        ax.errorbar([], [], color="0.6", marker="o", markerfacecolor="white", linestyle="none",
                    label="earlier deck (before cut A), seeds 1–2,\nits records' steady layers")
        ax.set_xscale("log", base=2)
        ax.set_xticks([20, 40, 80, 160])
        ax.set_xticklabels(["20", "40", "80", "160"])
        ax.set_xlabel("build plate (mean diameters)")
        ax.set_title({"packing": "steady layer's packing", "depth µm": "powder under the blade's tip (µm)",
                      "cover": "covered fraction"}[k], fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7.5, loc="upper right")
    fig.suptitle("Ti-6Al-4V 15–45 µm, 50 µm layers, 0.1 m/s, fused bed: the steady layer against the plate's length "
                 "(± SE; the shipped 40 D is 1.24 mm)", fontsize=10.5)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "plate_length.png"), dpi=110)


if __name__ == "__main__":
    main()
