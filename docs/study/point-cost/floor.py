#!/usr/bin/env python3
"""What a point from rest cannot skip: each run's CPU per block times its warm-up (max(0.3 s · v,
10 D) in blocks of 5 D) and the least window (8 blocks).

    python3 docs/study/point-cost/floor.py SWEEP_DIR     # results.csv and runs/<hash>/result.json
"""
import importlib.util, os, statistics, sys

# The runs and the cold warm-up in blocks, as the SE study reads them.
_spec = importlib.util.spec_from_file_location("settled_se", os.path.join(os.path.dirname(__file__), "settled_se.py"))
_settled = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_settled)

LEAST_WINDOW = 8


def main(d):
    rows = []
    for j in _settled.load(d).values():
        blocks = len(j["steady_state"]["block_mfr"])
        warmup = _settled.warmup_blocks(j)
        per_block = j["cpu_time"] / blocks
        rows.append((j["cpu_time"], per_block * (warmup + LEAST_WINDOW), per_block * LEAST_WINDOW, blocks, warmup))
    print(f"{len(rows)} runs; blocks median {statistics.median(r[3] for r in rows)}, "
          f"of them warm-up {statistics.median(r[4] for r in rows)}\n")
    print("| | CPU s median | mean |\n|---|---|---|")
    for i, name in enumerate(("each run as it ran", "its warm-up and the least window only",
                              "the least window only")):
        print(f"| {name} | {statistics.median(r[i] for r in rows):.2f} | {statistics.fmean(r[i] for r in rows):.2f} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
