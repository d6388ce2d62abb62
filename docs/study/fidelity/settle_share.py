#!/usr/bin/env python3
"""Share of a run's engine time spent settling the pile, per variant of a fidelity bench: what
sharing one settled pile between points (LIGGGHTS restart files) could save at most (BENCHMARKS.md
"Fidelity").

    python3 docs/study/fidelity/settle_share.py BENCH_DIR      # the --out of `sweep bench fidelity`

A run's settle is every `Loop time` of its log before the line `demsweep: settled at step N`,
its spread every one after.
"""
import csv
import os
import re
import statistics
import sys

LOOP = re.compile(r"^Loop time of ([0-9.eE+-]+) on")


def share(log):
    settle = spread = 0.0
    settled = False
    for line in open(log, errors="replace"):
        if line.startswith("demsweep: settled at step"):
            settled = True
        m = LOOP.match(line)
        if m:
            if settled:
                spread += float(m.group(1))
            else:
                settle += float(m.group(1))
    total = settle + spread
    return settle / total if settled and total > 0 else None


def main(bench):
    by_variant = {}
    for row in csv.DictReader(open(os.path.join(bench, "fidelity-runs.csv"))):
        log = os.path.join(bench, "runs", row["hash"], "log.liggghts")
        s = share(log) if os.path.exists(log) else None
        if s is not None:
            by_variant.setdefault(row["variant"], []).append(s)
    print("variant       runs  settle share of loop time: mean  min    max")
    for v, shares in by_variant.items():
        print(f"{v:<13} {len(shares):>4}  {statistics.mean(shares):>32.3f}  {min(shares):.3f}  {max(shares):.3f}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
