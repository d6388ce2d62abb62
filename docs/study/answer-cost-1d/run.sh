#!/usr/bin/env bash
# The answer's cost on LIGGGHTS, side by side on one machine: the truth (a 33-point lattice at
# about a quarter of the sweep's SE) and three ways to the answer of speed.toml's 1-D space,
# each its own sweep directory under OUT, started together, one LIGGGHTS run at a time each:
#   thesis  the thesis's way: scrambled-Halton points at the `thesis` preset, batches of 16,
#           judged by the default rule (to 320 points)
#   lds     the same design at the defaults (`fast`, the sweep's own precision)
#   adapt   `sweep adapt` at its defaults (runs at half the sweep's SE, to 480 points)
# Resumable: run it again and every directory resumes where it stopped.
#   bash docs/study/answer-cost-1d/run.sh [OUT]      # default /tmp/answer-cost-1d
#   python3 docs/study/answer-cost-1d/summary.py OUT
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-/tmp/answer-cost-1d}"
mkdir -p "$out"
base="$here/speed.toml"
sed -e 's/^name = "speed-1d"/name = "speed-1d-thesis"/' -e 's/^substrate = "rough"/&\nfidelity = "thesis"/' \
  "$base" > "$out/thesis.toml"
sed -e 's/^name = "speed-1d"/name = "speed-1d-truth"/' \
  -e 's/^substrate = "rough"/&\nprecision = "fixed"\nmfr_rel_se = 0.01\nmfr_abs_se = 0.003/' \
  "$base" > "$out/truth.toml"
cp "$base" "$out/speed.toml"

# One way: start it, or resume it when its directory exists.
way() {
  local cmd=$1 file=$2 dir=$3
  if [ -f "$dir/manifest.json" ]; then
    sweep resume "$dir" --jobs 1 -q
  else
    sweep "$cmd" "$file" --out "$dir" --jobs 1 -q
  fi
  echo "$dir: exit $?" >> "$out/exits.txt"
}
way lattice "$out/truth.toml" "$out/truth" &
way lds "$out/thesis.toml" "$out/thesis" &
way lds "$out/speed.toml" "$out/lds" &
way adapt "$out/speed.toml" "$out/adapt" &
wait
