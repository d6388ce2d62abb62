#!/usr/bin/env bash
# The platform gap (docs/study/layers.md "The platform gap"): the shipped machine point of
# sweeps/ti64-layers.toml, run again once the round blade rode a largest diameter over the feed
# platform and the wall (before, at no clearance, it ground the powder into the platform). Each
# case: label, layer thickness (mm), blade speed (m/s), and optionally a `[scene]` key set in the
# sweep file (`seed = 2`). The numerical checks of the machine point halve the timestep (0.165
# Rayleigh times), double the periodic depth (12 D), and halve, double and double again the build
# plate (20, 80, 160 D), and run the 80 D plate with a second seed. A case's keys are separated
# by ";". Resumable: a recorded case is skipped.
# Run from the repository's root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64-gap.sh [label]
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
cases="ti64-50um-0.1-gap 0.05 0.1
ti64-30um-0.1-gap 0.03 0.1
ti64-50um-0.2-gap 0.05 0.2
ti64-50um-0.05-gap 0.05 0.05
ti64-50um-0.1-gap-seed2 0.05 0.1 seed = 2
ti64-80um-0.1-gap 0.08 0.1
ti64-50um-0.1-gap-dt0.165 0.05 0.1 rayleigh_fraction = 0.165
ti64-50um-0.1-gap-depth12 0.05 0.1 depth_diameters = 12.0
ti64-50um-0.1-gap-plate20 0.05 0.1 plate_diameters = 20.0
ti64-50um-0.1-gap-plate80 0.05 0.1 plate_diameters = 80.0
ti64-50um-0.1-gap-plate160 0.05 0.1 plate_diameters = 160.0
ti64-50um-0.1-gap-plate80-seed2 0.05 0.1 plate_diameters = 80.0; seed = 2"
want=${1:-}
while read -r label thickness speed keys; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  cp sweeps/ti64-layers.toml "$toml"
  IFS=';' read -ra pairs <<< "$keys"
  for pair in "${pairs[@]}"; do
    pair=$(echo "$pair" | sed 's/^ *//; s/ *$//')
    [ -z "$pair" ] && continue
    sed -i "s/^layers = \([0-9]*\)$/layers = \1\n$pair/" "$toml"
    grep -q "^$pair$" "$toml"
  done
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json \
    --set layer_thickness=$thickness,blade_speed=$speed > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
