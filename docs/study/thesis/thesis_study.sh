#!/usr/bin/env bash
# The thesis's study on real LIGGGHTS (docs/study/thesis/README.md): the 4-D LDS sweep to 2,400 points,
# the 4-D lattice at levels 5, 6, 7, and an LDS over the blade speeds real machines use.
#
#   bash docs/study/thesis/thesis_study.sh [lds|lattice|slow|lds-0.3|slow-heap20|lds-heap20|adapt-240|lds-2400|lds-2400-warm|lds-seed777 ...]   (default: lds lattice slow)
#
# It takes hours on two cores and is meant to be cut off and started again: each sweep runs in
# WORK/<name> (default WORK=/tmp/thesis-study) with `sweep lds|lattice|adapt`, which continues a
# directory it finds; every SYNC_S seconds, and at the end, the sweep's slim record is copied to
# docs/study/thesis/<name>/: sweep.toml, summary.json and convergence.csv as they are,
# manifest.json, joblog.tsv and results.csv gzipped, and each run's result.json or failure.json
# (no decks, logs or dumps), loose while the sweep runs and packed in runs.tar.gz at its end. On a
# fresh clone the record is unpacked into WORK/<name> first, so `sweep` reuses every finished run.
# Commit docs/study/thesis/ to carry the study across machines.
#
# The LDS sweeps run with --hold 1000 so that they go on to their --max whatever the verdict (the
# thesis's figures need the whole space); `sweep report` then judges them with the default rule
# and with the thesis's (README "Reading the verdict").
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${SWEEP_BIN:-$PWD/target/release/sweep}
work=${WORK:-/tmp/thesis-study}
jobs=${JOBS:-2}
sync_s=${SYNC_S:-300}
record=docs/study/thesis
mkdir -p "$work" "$record"

# The sweep's files kept as they are, and the bulky ones kept gzipped.
plain=(sweep.toml summary.json convergence.csv batches.csv precision.json)
packed=(manifest.json joblog.tsv results.csv)

# Copy the slim record of sweep directory $1 into its record $2. Runs not in the record yet are
# copied loose into $2/runs (cheap to repeat while the sweep runs); pack_runs packs them.
record() {
  local from=$1 to=$2 f d h
  [ -f "$from/manifest.json" ] || return 0
  mkdir -p "$to/runs"
  for f in "${plain[@]}"; do
    [ -f "$from/$f" ] && cp "$from/$f" "$to/$f.tmp" && mv "$to/$f.tmp" "$to/$f"
  done
  for f in "${packed[@]}"; do
    [ -f "$from/$f" ] && gzip -9c "$from/$f" > "$to/$f.gz.tmp" && mv "$to/$f.gz.tmp" "$to/$f.gz"
  done
  for d in "$from"/runs/*/; do
    h=$(basename "$d")
    for f in result.json failure.json; do
      if [ -f "$d$f" ] && [ ! -f "$to/runs/$h/$f" ]; then
        mkdir -p "$to/runs/$h" && cp "$d$f" "$to/runs/$h/$f"
      fi
    done
  done
}

# Pack every run of sweep directory $1 (each result.json or failure.json) into $2/runs.tar.xz.NN,
# parts of at most 900 kB (no committed record file over 1 MB), in place of the loose copies.
pack_runs() {
  local from=$1 to
  [ -f "$from/manifest.json" ] || return 0
  to=$(cd "$2" && pwd)
  rm -f "$to"/runs.tar.xz.part.*
  (cd "$from" && find runs \( -name result.json -o -name failure.json \) -print0 | sort -z |
    tar cf - --null -T - | xz -9e -T1 | split -b 900k -d - "$to/runs.tar.xz.part.")
  for f in "$to"/runs.tar.xz.part.*; do mv "$f" "${f/.part./.}"; done
  rm -rf "$to/runs" "$to/runs.tar.gz"
}

# Unpack the record $1 into a new sweep directory $2.
restore() {
  local from=$1 to=$2 f
  mkdir -p "$to"
  for f in "${plain[@]}"; do [ -f "$from/$f" ] && cp "$from/$f" "$to/$f"; done
  for f in "${packed[@]}"; do [ -f "$from/$f.gz" ] && gunzip -c "$from/$f.gz" > "$to/$f"; done
  if compgen -G "$from/runs.tar.xz.[0-9]*" > /dev/null; then
    cat "$from"/runs.tar.xz.[0-9]* | xz -d | tar xf - -C "$to"
  fi
  # Runs copied loose by a session that did not reach its end.
  [ -d "$from/runs" ] && cp -r "$from/runs" "$to/"
  return 0
}

run_sweep() { # name, then the sweep command's arguments
  local name=$1; shift
  local dir=$work/$name
  if [ ! -d "$dir" ] && [ -f "$record/$name/manifest.json.gz" ]; then
    echo "study: restoring $name from $record/$name" >&2
    restore "$record/$name" "$dir"
  fi
  ( while sleep "$sync_s"; do record "$dir" "$record/$name"; done ) &
  local syncer=$!
  local start=$SECONDS rc=0
  # FORCE=1: continue a directory whose templates changed (runs whose decks did not change keep
  # their results; the others run again under their new hashes).
  if [ -n "${FORCE:-}" ] && [ -f "$dir/manifest.json" ]; then
    "$bin" resume "$dir" --jobs "$jobs" --force || rc=$?
  else
    "$bin" "$@" --out "$dir" --jobs "$jobs" || rc=$?
  fi
  kill "$syncer" 2>/dev/null || true
  "$bin" report "$dir" >/dev/null 2>&1 || true
  record "$dir" "$record/$name"
  pack_runs "$dir" "$record/$name"
  echo "study: $name exited $rc after $((SECONDS - start)) s" >&2
  printf '%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$name" "$rc" "$((SECONDS - start))" \
    "$("$bin" --version)" >> "$record/sessions.tsv"
  [ "$rc" -eq 130 ] && exit 130
  return 0
}

[ -f "$record/sessions.tsv" ] || printf 'ended\tsweep\texit\twall_s\tversion\n' > "$record/sessions.tsv"
order=("$@")
[ ${#order[@]} -gt 0 ] || order=(lds lattice slow)
for s in "${order[@]}"; do
  case $s in
    lds) run_sweep lds lds sweeps/thesis-lds.toml --max 2400 --hold 1000 ;;
    lattice) run_sweep lattice lattice sweeps/thesis-lattice.toml --levels 5,6,7 --hold 1000 ;;
    slow) run_sweep slow lds "$record/machine-speeds.toml" --hold 1000 ;;
    # The LDS again at the default warm-up of 0.3 s (`lds` ran at the conveyor's first, 0.15 s).
    lds-0.3) run_sweep lds-0.3 lds sweeps/thesis-lds.toml --max 2400 --hold 1000 ;;
    # The machine-speed LDS again on the recoater's definitions: a 20 mm heap at every D, the
    # layer packing over the gap plus the pockets' open depth.
    slow-heap20) run_sweep slow-heap20 lds "$record/machine-speeds.toml" --hold 1000 ;;
    # The thesis's 4-D LDS at one fixed heap (20 mm above the tip at every D): D's own index.
    lds-heap20) run_sweep lds-heap20 lds sweeps/thesis-lds.toml --max 400 --hold 1000 ;;
    # The same space by `sweep adapt`, at most 240 runs (a tenth of `lds`), judged by the default
    # rule: the verdict and the runs it took, against lds-heap20 (the same scene).
    adapt-240) run_sweep adapt-240 adapt sweeps/thesis-lds.toml --first 40 --batch 8 --max 240 ;;
    # The whole 2,400-point LDS again on today's defaults (the 20 mm heap, the sweep's precision,
    # cold starts): its core-hours against `lds-0.3` and `lds-heap20` (BENCHMARKS.md).
    lds-2400) run_sweep lds-2400 lds sweeps/thesis-lds.toml --max 2400 --hold 1000 ;;
    # The same with warm starts on: what they save as the design fills, and against lds-2400's
    # cold runs of the same points, what they move. (lds-2400-warm-share0 is its first 584
    # points before a warm start kept 0.6 of the cold warm-up: a record, not resumable.)
    lds-2400-warm)
      sed 's/^\[scene\]$/[scene]\nwarm_start = true/' sweeps/thesis-lds.toml > "$work/thesis-lds-warm.toml"
      run_sweep lds-2400-warm lds "$work/thesis-lds-warm.toml" --max 2400 --hold 1000 ;;
    # Its first 100 points again from rest with other particle seeds: how far two cold runs of a
    # point differ, the yardstick for lds-2400-warm against lds-2400.
    lds-seed777)
      sed 's/^\[scene\]$/[scene]\nseed = 777/' sweeps/thesis-lds.toml > "$work/thesis-lds-seed777.toml"
      run_sweep lds-seed777 lds "$work/thesis-lds-seed777.toml" --step 100 --max 100 --hold 1000 ;;
    *) echo "study: unknown sweep '$s' (expected lds, lattice, slow, lds-0.3, slow-heap20, lds-heap20, adapt-240, lds-2400, lds-2400-warm or lds-seed777)" >&2; exit 2 ;;
  esac
done
