#!/usr/bin/env bash
# The layers study's numerical check of the machine answer (docs/study/layers.md): the steady
# layer of Ti-6Al-4V 15–45 µm on a fused bed at 50 µm layers and 0.1 m/s (sweeps/ti64-layers.toml
# at its defaults, recorded by ti64-search.sh as record/ti64-50um-0.1-search6.json) with each
# numerical choice halved or doubled — the build plate halved (20 D) and doubled (80 D), the
# periodic depth doubled (12 D), the timestep halved (0.165 Rayleigh times) — and a second seed,
# the scatter they are judged against; the depth and timestep checks also at 30 µm layers (the
# cheapest steady case, record/ti64-30um-0.1-search6.json). Each case names its layer thickness
# (mm). Resumable: a recorded case is skipped. Run from the
# repository's root with target/release/sweep built (or SWEEP=path).
#   bash docs/study/layers/ti64-numerics.sh [label]
# The `-back` cases are a cost saving tried and not kept (docs/study/layers.md "The blade's back
# cut"): the blade built at the commit that had it, run by label,
#   git worktree add /tmp/blade-back dc712f2 && (cd /tmp/blade-back && cargo build --release)
#   SWEEP=/tmp/blade-back/target/release/sweep bash docs/study/layers/ti64-numerics.sh ti64-50um-0.1-search6-back
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
cases="ti64-50um-0.1-search6-seed2 0.05 seed = 2
ti64-50um-0.1-search6-plate20 0.05 plate_diameters = 20.0
ti64-30um-0.1-search6-depth12 0.03 depth_diameters = 12.0
ti64-30um-0.1-search6-dt0.165 0.03 rayleigh_fraction = 0.165
ti64-50um-0.1-search6-depth12 0.05 depth_diameters = 12.0
ti64-50um-0.1-search6-dt0.165 0.05 rayleigh_fraction = 0.165
ti64-50um-0.1-search6-plate80 0.05 plate_diameters = 80.0
ti64-50um-0.1-search6-back 0.05 seed = 12345
ti64-50um-0.1-search6-back-seed2 0.05 seed = 2"
want=${1:-}
while read -r label thickness key eq value; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  # The blade's back is not in the product: those cases run only when asked for by name.
  [ -z "$want" ] && [[ $label == *-back* ]] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  sed "s/^layers = \([0-9]*\)$/layers = \1\n$key = $value/" sweeps/ti64-layers.toml > "$toml"
  grep -q "^$key = $value$" "$toml"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set layer_thickness=$thickness,blade_speed=0.1 \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
