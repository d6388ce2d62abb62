#!/usr/bin/env python3
"""How much a warm-up of a given length biases MFR, in time and in travel.

    python3 docs/study/recoater/transient_bias.py RUNS_DIR [WINDOW_BLOCKS]

For each long run (no precision stop, warm-up 0) the block series y is measured as a point would
be after a warm-up of w: the mean of the next WINDOW_BLOCKS blocks (12: about what the 5 %
target needs at 1.4 m/s). Its bias is that mean over the run's tail (its last half) minus one.
The cases at one speed (D 1, 2 and 3 mm: at a fixed heap D has no effect of its own) are
averaged, and the bias is tabulated at warm-ups given in seconds and in heap lengths
((gap + heap_height) / tan 30°), so one can see which unit makes the transient the same at every
speed.
"""
import glob, json, math, os, statistics, sys

def cases(runs):
    for case in sorted(glob.glob(os.path.join(runs, "D*-v*"))):
        f = os.path.join(case, "result.json")
        if not os.path.isdir(case) or not os.path.exists(f):
            continue
        r = json.load(open(f))
        st, p = r["steady_state"], r["parameters"]
        d, v, gap = p["diameter"], p["blade_speed"], p["gap"]
        block_mm = st["block_diameters"] * d
        heap_len = (gap + p["heap_height"]) / math.tan(math.radians(30))
        yield d, v, p["heap_height"], block_mm, heap_len, st["block_mfr"]

def bias_at(y, block_mm, travel_mm, window):
    w = int(round(travel_mm / block_mm))
    tail = statistics.fmean(y[len(y) // 2:])
    if w + window > len(y) // 2 + window or tail <= 0:
        return None
    return statistics.fmean(y[w:w + window]) / tail - 1

def main():
    runs = sys.argv[1]
    window = int(sys.argv[2]) if len(sys.argv) > 2 else 12
    by_speed = {}
    for d, v, heap, block_mm, heap_len, y in cases(runs):
        by_speed.setdefault((v, heap), []).append((d, block_mm, heap_len, y))
    times = [0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6]
    lengths = [0.5, 1, 2, 3, 5, 8, 10]
    for unit, grid, to_mm in (("s", times, lambda v, h, x: x * v * 1e3),
                              ("heap lengths", lengths, lambda v, h, x: x * h)):
        print(f"\nMean bias of MFR (%) after a warm-up in {unit}, {window}-block window, against the tail:\n")
        print(f"| v m/s | heap mm | cases (D mm) | " + " | ".join(f"{x} {unit}" for x in grid) + " |")
        print("|---|---|---|" + "---|" * len(grid))
        for v, heap in sorted(by_speed):
            row = []
            for x in grid:
                b = [bias_at(y, bmm, to_mm(v, h, x), window) for _, bmm, h, y in by_speed[(v, heap)]]
                b = [e for e in b if e is not None]
                row.append(f"{100 * statistics.fmean(b):+.0f}" if len(b) == len(by_speed[(v, heap)]) else "–")
            ds = ", ".join(f"{d:g}" for d, *_ in by_speed[(v, heap)])
            print(f"| {v} | {heap:g} | {ds} | " + " | ".join(row) + " |")

if __name__ == "__main__":
    main()
