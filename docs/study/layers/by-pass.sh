#!/usr/bin/env bash
# A layers point run pass by pass and stopping once steady, against the same powder's single
# layer, one after the other in one run so that both see the same machine: the Ti-6Al-4V machine
# point (sweeps/ti64-layers.toml at 50 µm and 0.1 m/s, the shipped file, no hand-set key) and
# sweeps/ti64-machine.toml's single layer at 0.08 m/s; then the same at 30 µm and 0.05 m/s.
# Each run keeps its directory under runs/by-pass/ (its passes' logs, restarts, records), so an
# interrupted study goes on from each point's last pass. The records: record/by-pass-*.json.
#   bash docs/study/layers/by-pass.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
sweep=${SWEEP:-target/release/sweep}
out=docs/study/layers/record
mkdir -p "$out" runs/by-pass
one() { # label, sweep file, --set
  local label=$1 file=$2 set=$3
  [ -s "$out/$label.json" ] && return 0
  "$sweep" run "$file" --json --set "$set" --out "runs/by-pass/$label" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
}
one by-pass-50um-0.1 sweeps/ti64-layers.toml layer_thickness=0.05,blade_speed=0.1
one by-pass-single-0.08 sweeps/ti64-machine.toml blade_speed=0.08
one by-pass-30um-0.05 sweeps/ti64-layers.toml layer_thickness=0.03,blade_speed=0.05
one by-pass-single-0.05 sweeps/ti64-machine.toml blade_speed=0.05
