#!/usr/bin/env python3
"""CPU of sweep directories' runs against the first one's on the same design indices.

    python3 docs/study/thesis/lds_cost.py BASE_DIR [DIR ...]

Per directory: the runs with a CPU time (done or failed), their mean and median CPU s, the mean
over the indices the base also ran against the base's mean there, and the CPU-hours of the
thesis LDS's 2,304 runs (2,400 points less the 96 its screen closes) at that mean.
"""
import importlib.util, os, statistics, sys

# The runs of a sweep directory as compare.py reads them (index → its row, CPU, ...).
_spec = importlib.util.spec_from_file_location(
    "compare", os.path.join(os.path.dirname(__file__), "..", "warm-start", "compare.py"))
compare = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(compare)


def load(d):
    return {int(i): p["cpu"] for i, p in compare.load(d).items() if p["cpu"] == p["cpu"]}


base = load(sys.argv[1])
for d in sys.argv[1:]:
    v = load(d)
    common = [i for i in v if i in base]
    mv = statistics.fmean(v[i] for i in common)
    print(f"{os.path.basename(d.rstrip('/'))}: runs {len(v)}, CPU mean {statistics.fmean(v.values()):.2f} median {statistics.median(v.values()):.2f}; "
          f"on {len(common)} shared: mean {mv:.2f} vs base {statistics.fmean(base[i] for i in common):.2f}; 2,304 runs -> {2304*statistics.fmean(v.values())/3600:.2f} CPU-h")
