#!/usr/bin/env bash
# The layers study's loose bed at a second blade speed and layer thickness (docs/study/layers.md):
# Gaboriault et al.'s PS1 (sweeps/layers-gaboriault.toml, 100 µm at 0.1 m/s recorded by run.sh as
# record/PS1.json) at 0.2 m/s, and at 150 µm layers. Each case is `label blade_speed
# layer_thickness`; resumable: a recorded case is skipped. Run from the repository's root with
# target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/loose.sh [label]
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
cases="PS1-0.2 0.2 0.1
PS1-150um 0.1 0.15"
want=${1:-}
while read -r label speed thickness; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run sweeps/layers-gaboriault.toml --json \
    --set "blade_speed=$speed,layer_thickness=$thickness,friction=0.2,rolling_friction=0.1,surface_energy=4.667e-4" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
