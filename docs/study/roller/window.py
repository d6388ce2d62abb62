#!/usr/bin/env python3
"""The roller's speed ratio walked up again with the powder it ejects (docs/study/roller.md "The
speed ratio, with the powder thrown over the roller"): the study's cases roller-0 … roller-16 run
on today's deck into record/ejected/ (`OUT=docs/study/roller/record/ejected bash
docs/study/roller/run.sh roller-R`). For each ratio the mean of passes --from on (3 by default) of
numerics.py's measures with SE = SD/sqrt(n), the particles sent over the roller's top a pass
(from the run directories' logs while at hand, $RUNS, kept in record/ejected/ejected.tsv), and
the CPU. Draws window.png; prints the Markdown table.

    python3 docs/study/roller/window.py [--from 3]
"""
import argparse
import math
import os
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

from numerics import MEASURES, late_passes, logged_ejections, mean_se
from summary import thrown

HERE = Path(__file__).resolve().parent
RECORD = HERE / "record" / "ejected"
RATIOS = [0, 1, 2, 4, 8, 16]


def counts(runs):
    """{(label, pass): (particles sent over, their kg/m, particles in flight)} from ejected.tsv
    and any run directories at hand: sent over the roller's top (the log's line), and in flight
    over the plate when the layer is measured (summary.py's `thrown`)."""
    tsv = RECORD / "ejected.tsv"
    out = {}
    if tsv.exists():
        for line in tsv.read_text().splitlines()[1:]:
            label, k, n, m, flight = line.split("\t")
            out[(label, int(k))] = (int(n), float(m), int(flight))
    for r in RATIOS:
        label = f"roller-{r}"
        if not (runs / label).is_dir():
            continue
        flight = thrown(runs / label)
        for k, (n, m) in logged_ejections(runs / label).items():
            out[(label, k)] = (n, m, flight.get(k, -1))
    if out:
        with open(tsv, "w") as f:
            f.write("label\tpass\tparticles\tmass_kg\tin_flight\n")
            for (label, k), (n, m, flight) in sorted(out.items()):
                f.write(f"{label}\t{k}\t{n}\t{m}\t{flight}\n")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--from", dest="first", type=int, default=3)
    args = ap.parse_args()
    n_over = counts(Path(os.environ.get("RUNS", "/tmp/roller-study-ejected")))
    rows = []
    for r in RATIOS:
        f = RECORD / f"roller-{r}.json"
        if not f.exists():
            continue
        _, res, late = late_passes(f, args.first)
        if not late:
            continue
        cells = [mean_se([m(p) for p in late]) for _, m, _ in MEASURES]
        over = [n_over[(f"roller-{r}", p["k"])] for p in late if (f"roller-{r}", p["k"]) in n_over]
        rows.append((r, f"{late[0]['k']}–{late[-1]['k']}", cells, over, res.get("cpu_time", float("nan"))))
    head = ("| ratio | passes | " + " | ".join(n for n, _, _ in MEASURES)
            + " | particles over the top a pass | in flight after a pass | CPU s |")
    print(head + "\n|" + "---|" * (head.count("|") - 1))
    for r, span, cells, over, cpu in rows:
        text = " | ".join(f"{m:{fmt}} ± {se:{fmt}}" for (m, se), (_, _, fmt) in zip(cells, MEASURES))
        sent = "/".join(str(o[0]) for o in over) or "-"
        flight = "/".join(str(o[2]) for o in over) or "-"
        print(f"| {r} | {span} | {text} | {sent} | {flight} | {cpu:.0f} |")
    if not rows:
        return
    show = [("relative density", 0), ("cover", 2), ("roughness D", 3), ("ejected mg/m", 6)]
    fig, axes = plt.subplots(1, len(show), figsize=(13, 3.6))
    x = [r for r, *_ in rows]
    for ax, (name, i) in zip(axes, show):
        ax.errorbar(x, [c[i][0] for _, _, c, _, _ in rows],
                    yerr=[0 if math.isnan(c[i][1]) else c[i][1] for _, _, c, _, _ in rows],
                    marker="o", color="#3182bd", capsize=3)
        ax.set_xscale("symlog", linthresh=1)
        ax.set_xticks(RATIOS)
        ax.set_xticklabels([str(r) for r in RATIOS])
        ax.set_xlabel("speed ratio (surface speed / travel)")
        ax.set_title(name if name != "ejected mg/m" else "ejected over the top, mg per m a pass", fontsize=10)
        ax.grid(alpha=0.3)
    fig.suptitle(f"Roller, Ti-6Al-4V 15–45 µm, 50 µm layers, 0.1 m/s, 20 D plate: passes {args.first} on, "
                 "mean ± SE (one seed)", fontsize=10.5)
    fig.tight_layout()
    fig.savefig(HERE / "window.png", dpi=110)


if __name__ == "__main__":
    main()
