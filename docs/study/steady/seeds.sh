#!/usr/bin/env bash
# A point's MFR across pile seeds against the SE it reports: one point of a sweep file, at its
# defaults, run with scene seeds 1…N, each result kept as seeds/<label>/seed-<n>.json.
# Resumable: a recorded seed is skipped. Run from the repository's root with target/release/sweep
# built (or SWEEP=path).
#   bash docs/study/steady/seeds.sh N SWEEP_FILE NAME=VALUE,... LABEL [FIRST]
# (seeds FIRST…N; FIRST defaults to 1)
# The records here:
#   seeds.sh 30 sweeps/thesis-lds.toml friction=0.2,diameter=2.0,gap=4.2,blade_speed=1.3 f0.2-D2.0-g4.2-v1.3
#   seeds.sh 10 sweeps/thesis-lds.toml friction=0.1,diameter=1.0,gap=3.0,blade_speed=1.5 f0.1-D1.0-g3.0-v1.5
#   seeds.sh 10 sweeps/thesis-lds.toml friction=0.3,diameter=3.0,gap=4.5,blade_speed=1.2 f0.3-D3.0-g4.5-v1.2
#   seeds.sh 10 sweeps/ti64-machine.toml blade_speed=0.2 ti64-v0.2   (and v0.063, v0.02)
# and, once the SE was widened by Student's t and the deck stopped on it (docs/statistics.md):
#   seeds.sh 10 sweeps/ti64-machine.toml blade_speed=0.2 ti64-v0.2-t   (and v0.063, v0.08)
# and fresh seeds once the SE's batches doubled while their lag-1 autocorrelation is positive:
#   seeds.sh 15 sweeps/ti64-machine.toml blade_speed=0.063 ti64-v0.063-b0 11   (and 20 … 16)
set -euo pipefail
cd "$(dirname "$0")/../../.."
n=$1 file=$2 point=$3 label=$4 first=${5:-1}
out=docs/study/steady/seeds/$label
mkdir -p "$out"
for seed in $(seq "$first" "$n"); do
  [ -s "$out/seed-$seed.json" ] && continue
  toml=$(mktemp --suffix=.toml)
  sed "s/^\[scene\]$/&\nseed = $seed/" "$file" > "$toml"
  grep -q "^seed = $seed$" "$toml"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set "$point" \
    > "$out/seed-$seed.json.part" 2> "$out/seed-$seed.err" || true
  mv "$out/seed-$seed.json.part" "$out/seed-$seed.json"
  [ -s "$out/seed-$seed.err" ] || rm -f "$out/seed-$seed.err"
  rm -f "$toml"
  echo "$label seed $seed: $(( $(date +%s) - start )) s wall" >&2
done
