#!/usr/bin/env bash
# The roller study (docs/study/roller.md): sweeps/roller.toml's powder and machine point
# (Ti-6Al-4V 15–45 µm, 50 µm layers on a loose bed, 0.1 m/s), made affordable — a 20 D plate
# instead of 40 and 4 passes (8 for three cases) instead of 8 — spread by the round blade and by the roller at
# speed ratios from 0 up. Each case is `label profile ratio seed passes [a [scene] line]` (one
# halves the timestep at ratio 8, where the roller's surface runs at 0.8 m/s; three run the
# blade and two rollers to 8 passes), the most needed first — the last two, roller-8-dt2 and
# roller-0-8p, were not run for the study's CPU budget; resumable: a recorded case is
# skipped, and a case cut short goes on from its last finished pass (its run directory is kept
# under $RUNS). Run from the repository's root with target/release/sweep built (or SWEEP=path):
#   nice -n 10 bash docs/study/roller/run.sh [label]
# Each case leaves record/<label>.json (`sweep run --json`: the passes, the steady layer, the
# CPU) and record/<label>.err (its stderr); OUT=dir records elsewhere (a rerun on a changed deck
# beside the first records: OUT=docs/study/roller/record/load for the roller's load). Two runners may share the list (`run.sh` twice, or
# three, or `run.sh --reverse`): a case is taken by making $RUNS/<label>.lock, and a lock
# left by a runner that was stopped is removed by hand before running that case again.
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=${OUT:-docs/study/roller/record}
runs=${RUNS:-/tmp/roller-study$( [ -n "${OUT:-}" ] && echo "-$(basename "$OUT")")}
mkdir -p "$out" "$runs"
cases="roller-0 roller 0 1 4
roller-2 roller 2 1 4
blade blade 0 1 4
roller-4 roller 4 1 4
roller-1 roller 1 1 4
roller-8 roller 8 1 4
blade-s2 blade 0 2 4
roller-2-s2 roller 2 2 4
roller-16 roller 16 1 4
blade-8p blade 0 1 8
roller-2-8p roller 2 1 8
roller-8-dt2 roller 8 1 4 rayleigh_fraction = 0.165
roller-0-8p roller 0 1 8"
want=${1:-}
if [ "$want" = --reverse ]; then
  cases=$(tac <<< "$cases")
  want=
fi
while read -r label profile ratio seed passes extra; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  mkdir "$runs/$label.lock" 2> /dev/null || { echo "$label: taken"; continue; }
  file=$runs/$label.toml
  # The study's scene: a 20 D plate, 4 passes, the case's seed.
  sed -e 's/^layers = 8$/layers = '"$passes"'\nplate_diameters = 20\nseed = '"$seed"'\n'"$extra"'/' sweeps/roller.toml > "$file"
  if [ "$profile" = blade ]; then
    # The round blade of the same radius: the ratio is not read, blade_speed is the swept one.
    sed -i -e 's/^blade_profile = "roller"/blade_profile = "round"/' \
      -e '/^roller_speed_ratio/d' \
      -e 's/^blade_speed .*/blade_speed = { lo = 0.05, hi = 0.2, unit = "m\/s" }/' "$file"
    set_=blade_speed=0.1
  else
    set_=roller_speed_ratio=$ratio
  fi
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$file" --json --set "$set_" --out "$runs/$label" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"
