#!/usr/bin/env bash
# The layers study's machine question (docs/study/layers.md): Ti-6Al-4V 15–45 µm on a fused bed
# (sweeps/ti64-layers.toml, 24 passes, round blade): 50 µm layers at 0.1 m/s (record/ti64-50um-0.1.json), then 30 and
# 80 µm layers × 0.05 and 0.2 m/s (the lattice of 2, ti64/: the convergence over passes at two
# thicknesses and two speeds). Resumable: a recorded run is skipped, the sweep directory resumes.
# Run from the repository's root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
sweep=${SWEEP:-target/release/sweep}
out=docs/study/layers/record
mkdir -p "$out"
label=ti64-50um-0.1
if [ ! -s "$out/$label.json" ]; then
  "$sweep" run sweeps/ti64-layers.toml --json --set "layer_thickness=0.05,blade_speed=0.1" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
fi
"$sweep" lattice sweeps/ti64-layers.toml --levels 2 --jobs 1 --out docs/study/layers/ti64
