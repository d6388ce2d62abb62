#!/usr/bin/env bash
# The SE of a point's MFR from every block after the warm-up against the SE from the window MSER
# chose, and the conveyor's lid (BENCHMARKS.md "A point's SE, and what MSER's choice did to it"),
# on real runs:
#
#   SWEEP_OLD=/path/to/sweep-before bash docs/study/point-cost/settled_se.sh [STEP ...]
#
# Steps (default: all, in this order; each continues a directory it finds in WORK, default
# /tmp/se-study):
#   pairs   the first 100 points of sweeps/thesis-lds.toml from rest, twice (particle seeds
#           default and 777), with this tree's binary: two runs of each point, whose difference
#           over their combined SE should be about 1 (RMS).
#   warm    the same 100 points warm-started (pairs-warm): what a warm start saves and moves
#           under this SE, against pairs-default.
#   draws   the 24-point draws of the thesis space and of machine speeds (warm.sh's), cold and
#           to the fixed 5 %, with SWEEP_OLD (before: the window's SE, an open top) as
#           SPACE-before and this tree's binary as SPACE-now, one run at a time in the same
#           session: what the honest SE and the lid cost, and which points they bring back.
# Then: python3 docs/study/point-cost/settled_se.py pairs WORK/pairs-default WORK/pairs-777, and
# python3 docs/study/warm-start/compare.py (against docs/study/warm-start/record/*-long, unpacked).
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${SWEEP_BIN:-$PWD/target/release/sweep}
work=${WORK:-/tmp/se-study}
mkdir -p "$work"
steps=("$@")
[ ${#steps[@]} -gt 0 ] || steps=(pairs warm draws)
for s in "${steps[@]}"; do
  case $s in
    pairs)
      for seed in default 777; do
        file="$work/pairs-$seed.toml"
        if [ "$seed" = default ]; then cp sweeps/thesis-lds.toml "$file"
        else sed "s/^\[scene\]$/[scene]\nseed = $seed/" sweeps/thesis-lds.toml > "$file"; fi
        "$bin" lds "$file" --step 100 --max 100 --hold 1000 --jobs 1 --out "$work/pairs-$seed" > "$work/pairs-$seed.log" 2>&1 || true
      done ;;
    warm)
      sed 's/^\[scene\]$/[scene]\nwarm_start = true/' sweeps/thesis-lds.toml > "$work/pairs-warm.toml"
      "$bin" lds "$work/pairs-warm.toml" --step 100 --max 100 --hold 1000 --jobs 1 --out "$work/pairs-warm" > "$work/pairs-warm.log" 2>&1 || true ;;
    draws)
      : "${SWEEP_OLD:?draws needs SWEEP_OLD, the binary before the change}"
      cold='warm_start=false,precision="fixed"'
      for space in thesis slow; do
        SWEEP_BIN=$SWEEP_OLD WORK=$work bash docs/study/warm-start/warm.sh "$space-before=$space:$cold"
        SWEEP_BIN=$bin WORK=$work bash docs/study/warm-start/warm.sh "$space-now=$space:$cold"
      done ;;
    *) echo "settled_se.sh: unknown step '$s' (pairs, warm or draws)" >&2; exit 2 ;;
  esac
done
