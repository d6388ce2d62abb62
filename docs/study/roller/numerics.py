#!/usr/bin/env python3
"""The roller's numerics table (docs/study/roller.md "The roller's numerics") from the records
numerics.sh leaves: for each case, the mean of passes --from on (2 by default, to the last, 3) of
each pass's relative density, packing, cover, roughness, the roller's torque and turning power,
and the powder it ejected (over its top), with SE = SD/sqrt(n); then each variant against the
defaults at its ratio (seed 1): the difference and how many combined SEs it is — and the defaults
at seed 2 against seed 1, how far two realisations of the same numerics differ.

    python3 docs/study/roller/numerics.py [RECORD_DIR] [--from 2]
"""
import argparse
import json
import math
import os
import re
import statistics
from pathlib import Path

HERE = Path(__file__).resolve().parent
ORDER = ["r2", "r2-seed2", "r2-s64", "r2-s256", "r2-dt2", "r2-dt2-seed2", "r4", "r4-seed2", "r4-s64", "r4-s256", "r4-dt2"]
WHAT = {"": "defaults (128 segments, 0.33 Rayleigh)", "-s64": "64 segments", "-s256": "256 segments",
        "-dt2": "timestep halved (0.165 Rayleigh)", "-seed2": "defaults, seed 2",
        "-dt2-seed2": "timestep halved, seed 2"}
MEASURES = [
    ("relative density", lambda p: p["relative_density"], ".3f"),
    ("packing", lambda p: p["packing"], ".3f"),
    ("cover", lambda p: p["covered_fraction"], ".2f"),
    ("roughness D", lambda p: p["roughness_d"], ".1f"),
    ("torque µN·m/m", lambda p: p["roller"]["torque_nm_per_m"] * 1e6, ".2f"),
    ("turning mW/m", lambda p: p["roller"]["turning_power_w_per_m"] * 1e3, ".3f"),
    ("ejected mg/m", lambda p: p["roller"].get("ejected_kg_per_m", float("nan")) * 1e6, ".2f"),
]


def mean_se(values):
    values = [v for v in values if not math.isnan(v)]
    if not values:
        return float("nan"), float("nan")
    m = statistics.fmean(values)
    return m, (statistics.stdev(values) / math.sqrt(len(values)) if len(values) > 1 else float("nan"))


def logged_ejections(run_dir):
    """{pass: (particles, kg/m)} a run sent over the roller's top, from its pass logs (none when
    the run directory is not at hand)."""
    out = {}
    for log in sorted(run_dir.glob("log.pass.*")) if run_dir.is_dir() else []:
        for k, m, n in re.findall(r"^demsweep: ejected (\d+) mass (\S+) count (\S+)", log.read_text(), re.M):
            out[int(k)] = (int(float(n)), float(m))
    return out


def late_passes(path, first):
    """A record, its result (or a failure's measured passes) and that result's passes from
    `first` on."""
    rec = json.loads(path.read_text())
    r = rec.get("measured") or rec
    return rec, r, [p for p in (r.get("layers") or {}).get("passes") or [] if p["k"] >= first]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("record", nargs="?", default=str(HERE / "record" / "numerics"))
    ap.add_argument("--from", dest="first", type=int, default=2)
    args = ap.parse_args()
    record = Path(args.record)
    # The particles each pass sent over the roller, from the run directories' logs while they are
    # at hand ($RUNS), kept in ejected.tsv so that the count can be read from the records alone.
    runs = Path(os.environ.get("RUNS", "/tmp/roller-numerics"))
    tsv = record / "ejected.tsv"
    counts = {}
    if tsv.exists():
        for line in tsv.read_text().splitlines()[1:]:
            label, k, n, m = line.split("\t")
            counts[(label, int(k))] = (int(n), float(m))
    for label in ORDER:
        for k, over in logged_ejections(runs / label).items():
            counts[(label, k)] = over
    if counts:
        with open(tsv, "w") as f:
            f.write("label\tpass\tparticles\tmass_kg\n")
            for (label, k), (n, m) in sorted(counts.items()):
                f.write(f"{label}\t{k}\t{n}\t{m}\n")
    rows = {}
    for label in ORDER:
        f = record / f"{label}.json"
        if not f.exists():
            continue
        rec, r, late = late_passes(f, args.first)
        if not late:
            print(f"{label}: no passes measured ({rec.get('class')}: {rec.get('reason')})")
            continue
        rows[label] = ([mean_se([m(p) for p in late]) for _, m, _ in MEASURES], r.get("cpu_time", float("nan")),
                       f"{late[0]['k']}–{late[-1]['k']}")
    head = "| ratio | case | passes | " + " | ".join(n for n, _, _ in MEASURES) + " | ejected particles | CPU s |"
    print(head + "\n|" + "---|" * (head.count("|") - 1))
    for label, (cells, cpu, span) in rows.items():
        ratio, _, variant = label[1:].partition("-")
        text = " | ".join(f"{m:{fmt}} ± {se:{fmt}}" for (m, se), (_, _, fmt) in zip(cells, MEASURES))
        first, last = (int(x) for x in span.split("–"))
        n = [counts[(label, k)][0] for k in range(first, last + 1) if (label, k) in counts]
        ejected = "/".join(str(x) for x in n) if n else "-"
        print(f"| {ratio} | {WHAT['-' + variant if variant else '']} | {span} | {text} | {ejected} | {cpu:.0f} |")
    print()
    print("| ratio | against the defaults | " + " | ".join(n for n, _, _ in MEASURES) + " | ejected particles |")
    print("|" + "---|" * (len(MEASURES) + 3))
    for label, (cells, _, _) in rows.items():
        ratio, _, variant = label[1:].partition("-")
        # A variant at seed 2 against the defaults at seed 2.
        against = f"r{ratio}-seed2" if variant.endswith("seed2") and variant != "seed2" else f"r{ratio}"
        base = rows.get(against)
        if not variant or not base:
            continue
        diffs = []
        for (m, se), (mb, seb), (_, _, fmt) in zip(cells, base[0], MEASURES):
            comb = math.hypot(se, seb)
            z = (m - mb) / comb if comb > 0 else float("nan")
            diffs.append(f"{m - mb:+{fmt}} ({z:+.1f} SE)")
        # The particles sent over, counted as Poisson events: the difference of the two sums over
        # the same passes against the square root of their total.
        first, last = (int(x) for x in rows[label][2].split("–"))
        n = [sum(counts.get((l, k), (0, 0))[0] for k in range(first, last + 1)) for l in (label, against)]
        diffs.append(f"{n[0]} against {n[1]} ({(n[0] - n[1]) / math.sqrt(sum(n)):+.1f} σ)" if sum(n) else "-")
        print(f"| {ratio} | {WHAT['-' + variant]} | " + " | ".join(diffs) + " |")


if __name__ == "__main__":
    main()
