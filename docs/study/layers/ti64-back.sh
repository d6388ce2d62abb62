#!/usr/bin/env bash
# The round blade's back cut to where its arc has risen a tenth of a diameter (ROUND_BACK_RISE,
# src/scenes/layers/mod.rs), checked against the full back arc it replaced: the shipped machine
# point (sweeps/ti64-layers.toml at 50 µm layers and 0.1 m/s, the case recorded with the full
# arc as record/ti64-50um-0.1-search6.json at the default seed 12345 and -seed2.json at seed 2)
# run again at the same two seeds. Resumable: a
# recorded case is skipped. Run from the repository's root with target/release/sweep built (or
# SWEEP=path).
#   bash docs/study/layers/ti64-back.sh [label]
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
cases="ti64-50um-0.1-back 12345
ti64-50um-0.1-back-seed2 2"
want=${1:-}
while read -r label seed; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  sed "s/^layers = \([0-9]*\)$/layers = \1\nseed = $seed/" sweeps/ti64-layers.toml > "$toml"
  grep -q "^seed = $seed$" "$toml"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set layer_thickness=0.05,blade_speed=0.1 \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
