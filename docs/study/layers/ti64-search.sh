#!/usr/bin/env bash
# The layers study's fused-bed search (docs/study/layers.md): Ti-6Al-4V 15–45 µm on a fused bed
# (sweeps/ti64-layers.toml, round blade) whose first passes search for the steady depth of powder
# under the blade (`search_passes`) instead of building it up from the bare plate over 24 and more
# passes. Each case is `label layers search_passes layer_thickness blade_speed [scene key=value
# ...]`; `-halfdose` cases ran at half a fused bed's default dose (1.2 layers of solid a pass, the
# default before it was doubled). Resumable: a recorded case is skipped. Run from the repository's
# root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64-search.sh [label]
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
cases="ti64-50um-0.1-search4-halfdose 12 4 0.05 0.1 supply_factor=0.5
ti64-50um-0.1-search6-halfdose 14 6 0.05 0.1 supply_factor=0.5
ti64-50um-0.2-search6-halfdose 14 6 0.05 0.2 supply_factor=0.5
ti64-50um-0.1-search6 14 6 0.05 0.1
ti64-50um-0.2-search6 14 6 0.05 0.2
ti64-30um-0.1-search6 14 6 0.03 0.1
ti64-80um-0.1-search6 14 6 0.08 0.1
ti64-50um-0.05-search6 14 6 0.05 0.05"
want=${1:-}
while read -r label layers search thickness speed extra; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  lines="layers = $layers\nsearch_passes = $search"
  for kv in $extra; do lines="$lines\n${kv/=/ = }"; done
  toml=$(mktemp --suffix=.toml)
  sed "s/^layers = [0-9]*$/$lines/" sweeps/ti64-layers.toml > "$toml"
  grep -q "^search_passes = $search$" "$toml"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json \
    --set "layer_thickness=$thickness,blade_speed=$speed" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
