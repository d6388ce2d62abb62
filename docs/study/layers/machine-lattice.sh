#!/usr/bin/env bash
# The machine's question as a sweep: sweeps/ti64-layers.toml on its 3-level lattice (30, 55,
# 80 µm × 0.05, 0.1, 0.2 m/s; nine points, the shipped file, no hand-set key: every point
# searches for its depth from the bare plate, warm starts being off by default). Resumable: run it
# again and it goes on (each point from its last pass). Every finished point's result and each
# pass's record are copied to record/machine-lattice/ as they land, so a session that stops
# keeps what ran.
#   nice bash docs/study/layers/machine-lattice.sh
# It started on the templates of 37635eeb; a later template's text (417cb600 and c3221895 changed
# only the held loose bed's and the roller's branches) makes `resume` refuse. These decks render
# byte-identical on today's templates (the manifest's nine hashes unchanged under `--force`,
# checked on a copy), so FORCE=1 resumes with today's binary and re-runs nothing finished; or
# SWEEP=path to a binary built from 37635eeb. TAG=word runs another lattice beside it, in
# runs/machine-lattice-<word>/ and record/machine-lattice-<word>/ (the run of a later deck).
#   TAG=laid JOBS=2 SWEEP=/tmp/sweep-lattice nice bash docs/study/layers/machine-lattice.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
sweep=${SWEEP:-target/release/sweep}
jobs=${JOBS:-1}   # 2 on a two-core machine to itself: the first two points start cold
dir=runs/machine-lattice${TAG:+-$TAG}
out=docs/study/layers/record/machine-lattice${TAG:+-$TAG}
mkdir -p "$out"
copy() {
  for run in "$dir"/runs/*/; do
    [ -d "$run" ] || continue
    h=$(basename "$run"); mkdir -p "$out/$h"
    cp "$run"/pass.*.json "$run"/result.json "$run"/failure.json "$run"/warm-start.json "$out/$h/" 2>/dev/null || true
  done
}
( while sleep 60; do copy; done ) &
copier=$!
trap 'kill $copier 2>/dev/null || true; copy' EXIT
if [ -f "$dir/manifest.json" ]; then
  "$sweep" resume "$dir" --jobs "$jobs" ${FORCE:+--force} || true
else
  "$sweep" lattice sweeps/ti64-layers.toml --levels 3 --jobs "$jobs" --out "$dir" || true
fi
cp "$dir"/summary.json "$dir"/results.csv "$out/" 2>/dev/null || true
