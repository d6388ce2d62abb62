#!/usr/bin/env bash
# A point's MFR across pile seeds against the SE it reports (issue 47 item 16): one thesis-space
# point (sweeps/thesis-lds.toml's scene at its defaults; friction 0.2, D 2 mm, gap 4.2 mm (2.1 D),
# 1.3 m/s) run with scene seeds 1…N, each result kept as seeds/<point>/seed-<n>.json.
# Resumable: a recorded seed is skipped. Run from the repository's root with target/release/sweep
# built (or SWEEP=path).
#   bash docs/study/steady/seeds.sh [N]
set -euo pipefail
cd "$(dirname "$0")/../../.."
n=${1:-30}
point="friction=0.2,diameter=2.0,gap=4.2,blade_speed=1.3"
out=docs/study/steady/seeds/f0.2-D2-g4.2-v1.3
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
