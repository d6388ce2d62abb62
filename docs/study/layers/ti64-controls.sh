#!/usr/bin/env bash
# The layers study's controls for the machine answer (docs/study/layers.md): Ti-6Al-4V 15–45 µm
# on a fused bed at 50 µm layers and 0.1 m/s (sweeps/ti64-layers.toml, round blade; ti64.sh
# records it at half the default dose as record/ti64-50um-0.1-halfdose.json), spread instead with
# the flat blade (a box one diameter thick: the thesis's blade, a knife edge at 31 µm) at half the
# default dose, the same without cohesion (surface energy 0: the scene or the powder?), and the
# flat blade at the default dose (the dose?). Resumable: a recorded case is skipped. Run from the repository's
# root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64-controls.sh [label]
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
# label, extra --set values (or "-"), extra [scene] lines separated by ";"
cases="ti64-50um-0.1-flat-halfdose - blade_profile = \"flat\";supply_factor = 0.5
ti64-50um-0.1-flat-gamma0-halfdose surface_energy=0 blade_profile = \"flat\";supply_factor = 0.5
ti64-50um-0.1-flat - blade_profile = \"flat\""
want=${1:-}
while read -r label set scene; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  # As recorded: 24 passes, each a layer on the one before (no search).
  sed -e "s/^blade_profile = \"round\"$/${scene//;/\\n}/" \
    -e "s/^layers = [0-9]*$/layers = 24\nsearch_passes = 0/" sweeps/ti64-layers.toml > "$toml"
  grep -q "^search_passes = 0$" "$toml"
  grep -q "^blade_profile = \"flat\"$" "$toml"
  values="layer_thickness=0.05,blade_speed=0.1"
  [ "$set" != "-" ] && values="$values,$set"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set "$values" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
