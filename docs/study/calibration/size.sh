#!/usr/bin/env bash
# The size study of docs/study/calibration.md: the angle of repose poured from columns of three
# sizes, seeds 1..5 (scene.seed: the column's lattice jitter and the order of its sizes), one
# pour at a time, round by round (every size at seed 1, then at seed 2, ...), so that a study cut
# short still has every size. `316l` (the default): pour-316l-size.toml, 316L 15–45 µm at sliding
# = rolling friction = 0.5 and 0.01 mJ/m², columns of 500, 700 and 1,000 (scene.supply_factor
# 0.25, 0.35, 0.5), into record-size/. `spheres`: pour-2mm-size.toml, 2 mm steel spheres at
# sliding = rolling friction = 0.5, columns of 700, 1,000 and 1,400, into record-size-2mm/. Each
# pour's result.json is kept as n<N>-s<seed>.json; a pour already recorded is not run again
# (resumable: run it again after an interruption). size.py beside it reads a record.
#
#   nohup bash docs/study/calibration/size.sh [316l|spheres] >/tmp/size.log 2>&1 &   # from the root
#
# SWEEP: the binary (default target/release/sweep); SEEDS: the seeds (default "1 2 3 4 5");
# SIZES: supply factors.
set -euo pipefail
SWEEP=${SWEEP:-target/release/sweep}
SEEDS=${SEEDS:-1 2 3 4 5}
DIR=docs/study/calibration
case "${1:-316l}" in
  316l) FILE=pour-316l-size; REC=$DIR/record-size; SET=rolling_friction=0.5,surface_energy=1e-5; SIZES=${SIZES:-0.25 0.35 0.5} ;;
  spheres) FILE=pour-2mm-size; REC=$DIR/record-size-2mm; SET=rolling_friction=0.5; SIZES=${SIZES:-0.35 0.5 0.7} ;;
  *) echo "size.sh: unknown study $1: expected 316l or spheres" >&2; exit 2 ;;
esac
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$REC"
for seed in $SEEDS; do
  for f in $SIZES; do
    n=$(python3 -c "print(round(2000 * $f))")
    rec="$REC/n$n-s$seed.json"
    [ -s "$rec" ] && continue
    file="$WORK/n$n-s$seed.toml"
    sed -e "s/^supply_factor = .*/supply_factor = $f/" -e "s/^seed = .*/seed = $seed/" "$DIR/$FILE.toml" >"$file"
    echo "$(date -u +%H:%M:%S) pour of $n particles, seed $seed"
    if "$SWEEP" run "$file" --set "$SET" --json >"$rec.part" 2>"$WORK/err"; then
      mv "$rec.part" "$rec"
    else
      # A failed pour is recorded as failed (its one-line reason), not run again.
      python3 -c 'import json,sys; print(json.dumps({"failed": open(sys.argv[1]).read().strip()}))' "$WORK/err" >"$rec"
      rm -f "$rec.part"
    fi
  done
done
