#!/usr/bin/env bash
# Ten seeds of the point of docs/study/warmup-um/numerics.sh (sweeps/ti64-machine.toml at
# 0.08 m/s, every numerical key at its default): whether the SE the point reports covers the
# scatter between seeds (docs/study/warmup-um.md "The numerical choices at 35 µm"). Seeds 1 and
# 2 are numerics.sh's `default` and `seed2`. Resumable: a recorded seed is skipped.
#   bash docs/study/warmup-um/seeds.sh [SWEEP_BIN] [SEED...]   (default seeds 3–10)
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${1:-target/release/sweep}
shift || true
seeds=${*:-3 4 5 6 7 8 9 10}
out=docs/study/warmup-um/numerics
mkdir -p "$out"
for seed in $seeds; do
  label=seed$seed
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  sed "s/^\[scene\]$/[scene]\nseed = $seed/" sweeps/ti64-machine.toml > "$toml"
  grep -q "^seed = $seed$" "$toml"
  # A wall-clock guard for a shared machine, not a numerical choice.
  printf '\n[run]\ntimeout_s = 7200\n' >> "$toml"
  if "$bin" run "$toml" --json --set blade_speed=0.08 > "$out/$label.json.part" 2> "$out/$label.err"; then
    mv "$out/$label.json.part" "$out/$label.json"
  else
    echo "$label: failed (see $out/$label.err)" >&2
  fi
  rm -f "$toml"
done
