#!/usr/bin/env bash
# MFR against the gap at a fixed heap, for the Beverloo-like fit (gaps.py), and the monolayer
# ceiling on a smooth plate (gaps of D to 1.8 D). One point at a time, each in its own directory:
# resumable (a finished point is kept).
#   bash docs/study/recoater/gaps.sh [SWEEP_BIN]
# Environment: OUT (gaps-runs), DIAMETER (2, mm), SPEED (0.4, m/s), SUBSTRATE (smooth),
# GAPS_D (gaps in D: "1.2 1.5 2 2.5 3 4 5 6").
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
bin=${1:-sweep}
out=${OUT:-$here/gaps-runs}
d=${DIAMETER:-2}
v=${SPEED:-0.4}
substrate=${SUBSTRATE:-smooth}
mkdir -p "$out"
sweep=$out/$substrate.toml
cat > "$sweep" <<TOML
name = "gaps"
[parameters]
gap = { lo = 1.0, hi = 20.0, unit = "mm" }
diameter = { value = $d, unit = "mm" }
blade_speed = { value = $v, unit = "m/s" }
heap_height = { value = 20, unit = "mm" }
friction = 0.2
[scene]
layout = "conveyor"
substrate = "$substrate"
[run]
timeout_s = 7200
TOML
for g in ${GAPS_D:-1.2 1.5 2 2.5 3 4 5 6}; do
  gap=$(python3 -c "print(round($g*$d, 6))")
  case_dir=$out/$substrate-D$d-v$v-g$g
  [ -f "$case_dir/result.json" ] && continue
  [ -f "$case_dir/failure.json" ] && ! grep -q '"timed-out"' "$case_dir/failure.json" && continue
  echo "$substrate, D $d mm, v $v m/s, gap $g D" >&2
  "$bin" run "$sweep" --set "gap=$gap" --out "$case_dir" --json > /dev/null || true
done
