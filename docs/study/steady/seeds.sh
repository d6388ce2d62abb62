#!/usr/bin/env bash
# A point's MFR across pile seeds against the SE it reports: thesis-space points
# (sweeps/thesis-lds.toml's scene at its defaults) run with scene seeds 1…N, each result kept as
# seeds/<point>/seed-<n>.json. The default point is friction 0.2, D 2 mm, gap 4.2 mm (2.1 D),
# 1.3 m/s. Resumable: a recorded seed is skipped. Run from the repository's root with
# target/release/sweep built (or SWEEP=path).
#   bash docs/study/steady/seeds.sh [N [friction diameter gap blade_speed]]
set -euo pipefail
cd "$(dirname "$0")/../../.."
n=${1:-30}
f=${2:-0.2} d=${3:-2.0} g=${4:-4.2} v=${5:-1.3}
point="friction=$f,diameter=$d,gap=$g,blade_speed=$v"
out=docs/study/steady/seeds/f$f-D$d-g$g-v$v
mkdir -p "$out"
for seed in $(seq 1 "$n"); do
  [ -s "$out/seed-$seed.json" ] && continue
  toml=$(mktemp --suffix=.toml)
  sed "s/^layout = \"conveyor\".*$/&\nseed = $seed/" sweeps/thesis-lds.toml > "$toml"
  grep -q "^seed = $seed$" "$toml"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$toml" --json --set "$point" \
    > "$out/seed-$seed.json.part" 2> "$out/seed-$seed.err" || true
  mv "$out/seed-$seed.json.part" "$out/seed-$seed.json"
  [ -s "$out/seed-$seed.err" ] || rm -f "$out/seed-$seed.err"
  rm -f "$toml"
  echo "seed $seed: $(( $(date +%s) - start )) s wall" >&2
done
