#!/usr/bin/env bash
# The layers study's machine question (docs/study/layers.md): Ti-6Al-4V 15–45 µm on a fused bed
# (sweeps/ti64-layers.toml) at 30 and 80 µm layers × 0.05 and 0.2 m/s (the lattice of 2: the
# convergence over passes at two thicknesses and two speeds), then 50 µm at both speeds.
# Resumable: the sweep directory resumes where it stopped; a recorded 50 µm run is skipped. Run
# from the repository's root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
sweep=${SWEEP:-target/release/sweep}
"$sweep" lattice sweeps/ti64-layers.toml --levels 2 --jobs 1 --out docs/study/layers/ti64
out=docs/study/layers/record
mkdir -p "$out"
for v in 0.05 0.2; do
  label=ti64-50um-$v
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  "$sweep" run sweeps/ti64-layers.toml --json --set "layer_thickness=0.05,blade_speed=$v" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
done
