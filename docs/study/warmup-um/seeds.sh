#!/usr/bin/env bash
# Whether the SE a real powder's point reports is honest at the slowest speed of
# sweeps/ti64-machine.toml (docs/study/warmup-um.md "The SE between seeds at four speeds"): its
# point at 0.02 m/s, every `[scene]` numerical key at its default, ten scene seeds (about
# 870 CPU s each). The other speeds' seeds are docs/study/steady/seeds.sh's (0.063, 0.2 m/s)
# and numerics.sh's (0.08 m/s). Resumable: a recorded seed is skipped.
#   bash docs/study/warmup-um/seeds.sh [SWEEP_BIN]
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${1:-target/release/sweep}
for speed in 0.02; do
  out=docs/study/warmup-um/seeds/v$speed
  mkdir -p "$out"
  for seed in 1 2 3 4 5 6 7 8 9 10; do
    label=seed$seed
    [ -s "$out/$label.json" ] && { echo "v$speed $label: recorded"; continue; }
    toml=$(mktemp --suffix=.toml)
    sed "s/^\[scene\]$/[scene]\nseed = $seed/" sweeps/ti64-machine.toml > "$toml"
    grep -q "^seed = $seed$" "$toml"
    # A wall-clock guard, not a numerical choice: this machine is shared.
    printf '\n[run]\ntimeout_s = 14400\n' >> "$toml"
    start=$(date +%s)
    if "$bin" run "$toml" --json --set blade_speed=$speed > "$out/$label.json.part" 2> "$out/$label.err"; then
      mv "$out/$label.json.part" "$out/$label.json"
    else
      echo "v$speed $label: failed (see $out/$label.err)" >&2
    fi
    rm -f "$toml"
    echo "v$speed $label: $(( $(date +%s) - start )) s wall" >&2
  done
done
