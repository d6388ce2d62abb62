#!/usr/bin/env bash
# A cost saving tried and not kept (docs/study/layers.md "The blade's back cut"): the round
# blade's arc cut behind its tip where it has risen a tenth of a mean diameter, its back face
# vertical from there, so that the blade clears the feed sooner and the next dose goes in while
# it still crosses the plate (13 % fewer steps at the machine point). The shipped machine point
# (sweeps/ti64-layers.toml at 50 µm layers and 0.1 m/s; with the full arc
# record/ti64-50um-0.1-search6.json at the default seed 12345 and -seed2.json at seed 2) run
# again with the cut blade. The blade is not in the product: build the commit that had it,
#   git worktree add /tmp/blade-back dc712f2 && (cd /tmp/blade-back && cargo build --release)
#   SWEEP=/tmp/blade-back/target/release/sweep bash docs/study/layers/ti64-back.sh [label]
# from the repository's root. Resumable: a recorded case is skipped.
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
: "${SWEEP:?set SWEEP to a sweep built at dc712f2 (see the header)}"
cases="ti64-50um-0.1-search6-back 12345
ti64-50um-0.1-search6-back-seed2 2"
want=${1:-}
while read -r label seed; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  toml=$(mktemp --suffix=.toml)
  sed "s/^layers = \([0-9]*\)$/layers = \1\nseed = $seed/" sweeps/ti64-layers.toml > "$toml"
  grep -q "^seed = $seed$" "$toml"
  start=$(date +%s)
  "$SWEEP" run "$toml" --json --set layer_thickness=0.05,blade_speed=0.1 \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rm -f "$toml"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
