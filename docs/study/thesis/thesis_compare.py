#!/usr/bin/env python3
"""LDS against lattice (thesis Fig. 4.20 and 4.22 on one picture), docs/study/thesis/README.md.

    python3 docs/study/thesis/thesis_compare.py OUT.png REF.csv LABEL=convergence.csv ...

Each LABEL=convergence.csv is one design's convergence.csv (from `sweep report`, or saved by
`docs/study/thesis/thesis_tables.py --save`). REF.csv's last space is the reference (the best estimate of
the truth); the band around it is ±5 % of each statistic's scale, the scaled rule's tolerance
(mean: max(|mean|, std); std; skewness: max(|skewness|, 1); kurtosis). Needs matplotlib.
"""
import csv, sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

STATS = ["mean", "std", "skewness", "kurtosis"]
TOL = 0.05
MARKERS = ["o", "s", "^", "D", "v"]


def rows(path):
    return list(csv.DictReader(open(path)))


def scale(stat, ref):
    m, s, k, ku = (float(ref[x]) for x in STATS)
    return {"mean": max(abs(m), s), "std": s, "skewness": max(abs(k), 1.0), "kurtosis": ku}[stat]


def main():
    out, ref_path, designs = sys.argv[1], sys.argv[2], [a.split("=", 1) for a in sys.argv[3:]]
    ref = rows(ref_path)[-1]
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    for ax, stat in zip(axes.flat, STATS):
        r, half = float(ref[stat]), TOL * scale(stat, ref)
        ax.axhspan(r - half, r + half, color="0.5", alpha=0.18, lw=0)
        ax.axhline(r, color="0.35", lw=1)
        for k, (label, path) in enumerate(designs):
            rs = [x for x in rows(path) if x[stat]]
            n = [int(x["n"]) for x in rs]
            v = [float(x[stat]) for x in rs]
            lo = [vi - float(x[stat + "_lo"]) for vi, x in zip(v, rs)]
            hi = [float(x[stat + "_hi"]) - vi for vi, x in zip(v, rs)]
            # Offset the designs a little so their intervals do not hide each other.
            nx = [ni * (1 + 0.012 * (k - (len(designs) - 1) / 2)) for ni in n]
            ax.errorbar(nx, v, yerr=[lo, hi], marker=MARKERS[k % len(MARKERS)], ms=5, capsize=3, lw=1, label=label)
        ax.set_xscale("log")
        ax.set_xticks([400, 625, 800, 1296, 2400])
        ax.get_xaxis().set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.minorticks_off()
        ax.set_title(f"{stat} of MFR")
        ax.set_xlabel("N (runs in the space)")
        ax.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=9, loc="best")
    fig.suptitle(f"MFR statistics against N, 95 % bootstrap intervals; grey: reference ({ref['space']}) "
                 f"±{100 * TOL:.0f} % of each statistic's scale", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
