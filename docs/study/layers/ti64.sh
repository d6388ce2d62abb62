#!/usr/bin/env bash
# The layers study's machine question (docs/study/layers.md), laid layer on layer: Ti-6Al-4V
# 15–45 µm on a fused bed (sweeps/ti64-layers.toml's powder and round blade) at 50 µm layers and
# 0.1 m/s, 24 passes each on the one before from the bare plate, no search, at half a fused
# bed's default dose (1.2 layers of solid a pass; record/ti64-50um-0.1-halfdose.json). The machine's answers over layer thickness and speed, with the
# search, are ti64-search.sh's. Resumable: a recorded run is skipped. Run from the repository's
# root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
label=ti64-50um-0.1-halfdose
if [ ! -s "$out/$label.json" ]; then
  toml=$(mktemp --suffix=.toml)
  sed "s/^layers = [0-9]*$/layers = 24\nsearch_passes = 0\nsupply_factor = 0.5/" sweeps/ti64-layers.toml > "$toml"
  grep -q "^search_passes = 0$" "$toml"
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set "layer_thickness=0.05,blade_speed=0.1" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
fi
