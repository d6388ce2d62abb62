#!/usr/bin/env bash
# The roller's numerics (docs/study/roller.md "The roller's numerics"): at the study's machine
# point (sweeps/roller.toml: Ti-6Al-4V 15–45 µm, 50 µm layers on a loose bed, 0.1 m/s, a 2.5 mm
# roller, seed 1) at speed ratios 2 and 4, the roller's circle cut in half and twice its 128
# segments (scene.roller_segments 64 and 256) and the timestep halved (rayleigh_fraction 0.33 →
# 0.165), each beside the same point at the defaults. Shortened further than run.sh to be
# affordable beside other work: a 10 D plate (the tool's least; run.sh's 20 D, the shipped 40 D)
# and 3 passes (run.sh's 4), so the figures are passes 2–3. Each case is `label ratio segments
# rayleigh_fraction seed`, the most needed first — then the defaults at a second seed, which
# measure how far two realisations of the same numerics differ, the scale a change of the
# numerics is read against, and the halved step at ratio 2 again at that seed; resumable as run.sh is (a recorded case is skipped,
# a case cut short goes on from its last finished pass, its run directory under $RUNS). Run from
# the repository's root with target/release/sweep built (or SWEEP=path):
#   OUT=docs/study/roller/record/numerics nice -n 10 bash docs/study/roller/numerics.sh [label]
# Each case leaves $OUT/<label>.json (`sweep run --json`) and $OUT/<label>.err; then
#   python3 docs/study/roller/numerics.py $OUT     # the table
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=${OUT:-docs/study/roller/record/numerics}
runs=${RUNS:-/tmp/roller-numerics}
mkdir -p "$out" "$runs"
cases="r2 2 128 0.33 1
r4 4 128 0.33 1
r4-dt2 4 128 0.165 1
r2-dt2 2 128 0.165 1
r4-s64 4 64 0.33 1
r2-s64 2 64 0.33 1
r4-s256 4 256 0.33 1
r2-s256 2 256 0.33 1
r2-seed2 2 128 0.33 2
r4-seed2 4 128 0.33 2
r2-dt2-seed2 2 128 0.165 2"
want=${1:-}
while read -r label ratio segments fraction seed; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  mkdir "$runs/$label.lock" 2> /dev/null || { echo "$label: taken"; continue; }
  file=$runs/$label.toml
  sed -e 's/^layers = 8$/layers = 3\nplate_diameters = 10\nseed = '"$seed"'\nroller_segments = '"$segments"'\nrayleigh_fraction = '"$fraction"'/' \
    sweeps/roller.toml > "$file"
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$file" --json --set "roller_speed_ratio=$ratio" --out "$runs/$label" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  rmdir "$runs/$label.lock"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
