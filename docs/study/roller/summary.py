#!/usr/bin/env python3
"""The roller study's table (docs/study/roller.md) from its records.

For each record/<label>.json (`sweep run --json`, a result or a failure with its measured
passes): every pass's relative density, packing, depth, cover and roughness, the mean of the
passes from --from on with its SE (SD/sqrt(n), the passes read as independent as a loose bed's
are, docs/layers.md), and the point's CPU seconds. With the run directories at hand ($RUNS,
/tmp/roller-study by default) it also counts, in each pass's layer dump, the particles on the plate
whose centre stands more than two mean diameters above the tip's height — powder the spreader
threw (still in flight when the layer is measured, a fall of 10 D after the pass) or carried over
itself onto the layer it left — and keeps that count in record/thrown.tsv, so that the table can be made
again from the records alone.

    python3 docs/study/roller/summary.py [--from 3]
"""
import argparse
import json
import math
import os
import re
import statistics
from pathlib import Path

HERE = Path(__file__).resolve().parent
RECORD = HERE / "record"
ORDER = [
    "blade", "blade-s2", "blade-8p", "roller-0", "roller-0-8p", "roller-1", "roller-2", "roller-2-s2",
    "roller-2-8p", "roller-4", "roller-8", "roller-8-dt2", "roller-16",
]


def result_of(record):
    """The result in a record: the run's, or the measured passes of a run that failed."""
    return record.get("measured") or record


def thrown(run_dir):
    """Per pass k: particles on the plate after pass k whose centre is 2 D above the tip's height."""
    counts = {}
    for deck in sorted(run_dir.glob("in.pass.*")):
        k = int(deck.suffix[1:])
        tip = re.search(rf"^fix blade{k} .* move 0 0 (\S+)", deck.read_text(), re.M)
        dump = run_dir / f"dump.layer.{k}"
        if not tip or not dump.exists():
            continue
        tip = float(tip.group(1))
        lines = dump.read_text().splitlines()
        start = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS")) + 1
        rows = [l.split() for l in lines[start:] if l.strip()]
        if not rows:
            counts[k] = 0
            continue
        # Two mean diameters clear of the tip: not a layer's top dilated behind the spreader.
        d = 2.0 * statistics.fmean(float(r[4]) for r in rows)
        counts[k] = sum(1 for r in rows if float(r[3]) > tip + 2.0 * d)
    return counts


def mean_se(values):
    n = len(values)
    if n == 0:
        return float("nan"), float("nan")
    m = statistics.fmean(values)
    return m, (statistics.stdev(values) / math.sqrt(n) if n > 1 else float("nan"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--from", dest="first", type=int, default=3, help="first pass of the mean")
    ap.add_argument("--markdown", action="store_true", help="one table row a case")
    args = ap.parse_args()
    runs = Path(os.environ.get("RUNS", "/tmp/roller-study"))
    tsv = RECORD / "thrown.tsv"
    kept = {}
    if tsv.exists():
        for line in tsv.read_text().splitlines()[1:]:
            label, k, n = line.split("\t")
            kept[(label, int(k))] = int(n)
    labels = [l for l in ORDER if (RECORD / f"{l}.json").exists()]
    for label in labels:
        if (runs / label).is_dir():
            for k, n in thrown(runs / label).items():
                kept[(label, k)] = n
    with open(tsv, "w") as f:
        f.write("label\tpass\tparticles_above_tip\n")
        for (label, k), n in sorted(kept.items()):
            f.write(f"{label}\t{k}\t{n}\n")

    if args.markdown:
        print(
            f"| case | ratio | passes | judged | relative density | packing | depth µm | cover | roughness D "
            f"| in flight | CPU s |\n|---|---|---|---|---|---|---|---|---|---|---|"
        )
    else:
        print("label        ratio  status     CPU s  pass: rel.density packing depth_um cover rough_D thrown")
    for label in labels:
        record = json.loads((RECORD / f"{label}.json").read_text())
        r = result_of(record)
        layers = r.get("layers") or {}
        passes = layers.get("passes") or []
        ratio = r.get("parameters", {}).get("roller_speed_ratio", float("nan"))
        status = "steady" if layers.get("steady") else (record.get("class") or "not steady")
        late = [p for p in passes if p["k"] >= args.first]
        if args.markdown:
            def cell(key, scale=1.0, fmt=".3f"):
                m, se = mean_se([p[key] * scale for p in late])
                return f"{m:{fmt}} ± {se:{fmt}}"
            th = [kept[(label, p["k"])] for p in late if (label, p["k"]) in kept]
            print(
                f"| {label} | {'—' if label.startswith('blade') else f'{ratio:g}'} | {args.first}–{passes[-1]['k'] if passes else '-'} | {status} "
                f"| {cell('relative_density')} | {cell('packing')} | {cell('effective_thickness_m', 1e6, '.0f')} "
                f"| {cell('covered_fraction', 1.0, '.2f')} | {cell('roughness_d', 1.0, '.1f')} "
                f"| {sum(th) / len(th) if th else float('nan'):.1f} | {r.get('cpu_time', float('nan')):.0f} |"
            )
            continue
        print(f"{label:<12} {ratio:>5}  {status:<9} {r.get('cpu_time', float('nan')):>6.0f}")
        for p in passes:
            print(
                f"{'':>36}{p['k']}: {p['relative_density']:.3f} {p['packing']:.3f} "
                f"{p['effective_thickness_m'] * 1e6:.1f} {p['covered_fraction']:.2f} {p['roughness_d']:.2f} "
                f"{kept.get((label, p['k']), '-')}"
            )
        cells = []
        for key, scale, fmt in [
            ("relative_density", 1, ".3f"),
            ("packing", 1, ".3f"),
            ("effective_thickness_m", 1e6, ".1f"),
            ("covered_fraction", 1, ".3f"),
            ("roughness_d", 1, ".2f"),
        ]:
            m, se = mean_se([p[key] * scale for p in late])
            cells.append(f"{key} {m:{fmt}} ± {se:{fmt}}")
        th = [kept[(label, p["k"])] for p in late if (label, p["k"]) in kept]
        cells.append(f"thrown {statistics.fmean(th):.1f}" if th else "thrown -")
        print(f"{'':>12} passes {args.first}+: " + ", ".join(cells))


if __name__ == "__main__":
    main()
