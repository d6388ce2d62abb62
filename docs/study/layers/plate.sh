#!/usr/bin/env bash
# The layers study's numerical check (docs/study/layers.md): PS1 with the build plate halved
# (12 D) and doubled (48 D) against the 24 D of run.sh's PS1. Resumable: a recorded case is
# skipped. Run from the repository's root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/plate.sh [12|48]
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
for n in ${1:-12 48}; do
  label=PS1-plate$n
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  sed "s/^plate_diameters = 24$/plate_diameters = $n/" sweeps/layers-gaboriault.toml > "$toml"
  grep -q "^plate_diameters = $n$" "$toml"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set blade_speed=0.1 \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done
