#!/bin/sh
# The verdict on real LIGGGHTS runs (BENCHMARKS.md "Verdict against the truth", LIGGGHTS part):
# at least 100 points of the thesis's 4-D space, then the emulator's cross-validated error
# against the per-point noise, and the noise share of MFR's variance.
#
#   scripts/verdict_liggghts.sh [OUT_DIR] [POINTS]      # default runs/verdict-liggghts, 100
#
# Runs `sweep lds sweeps/thesis-lds.toml` in steps of 50 up to POINTS with tolerance 0 (every
# point runs; two LIGGGHTS processes at a time), or reuses OUT_DIR if it holds a sweep, then
# `sweep report` and prints the numbers from summary.json. The noise share needs results that
# record `mfr_se`; without it the script says so.
set -eu
OUT=${1:-runs/verdict-liggghts}
N=${2:-100}
SWEEP=${SWEEP:-target/release/sweep}
if [ ! -f "$OUT/manifest.json" ]; then
    "$SWEEP" lds sweeps/thesis-lds.toml --step 50 --max "$N" --tolerance 0 --jobs 2 -q --out "$OUT" || true
fi
"$SWEEP" report "$OUT" > /dev/null
python3 - "$OUT/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
e = s.get("emulator")
print(f"points done: {s['counts']['done']}, failed: {s['counts']['failed']}")
if e is None:
    print("no emulator (too few done points)")
else:
    cv = e["cross_validation"]
    print(f"emulator LOO: RMSE {cv['rmse']:.4f} against per-point noise {cv['noise_se']:.4f}; "
          f"Q2 {cv['q2']:.3f}; {100*cv['coverage95']:.0f}% inside 95% band; {e['points']} points")
    raw, emu = s["statistics"], e["statistics"]
    for k, name in enumerate(["mean", "std", "skewness", "kurtosis"]):
        iv = emu["intervals"][k]
        print(f"  {name:9s} raw {raw[name]} emulator {emu['statistics'][name]} [{iv['lo']}, {iv['hi']}]")
    print(f"zero region: {100*e['zero_fraction']:.1f}% (sure: {100*e['zero_fraction_sure']:.1f}%)")
last = s["spaces"][-1] if s["spaces"] else None
if last and last.get("noise"):
    n = last["noise"]
    print(f"noise share of MFR variance: {100*n['noise_share']:.1f}% ({n['points_with_se']} points with mfr_se); "
          f"std raw {n['std_raw']:.4f}, without noise {n['std_without_noise']:.4f}")
else:
    print("no point records mfr_se: the noise share cannot be split")
print(s["sensitivity_note"])
PY
