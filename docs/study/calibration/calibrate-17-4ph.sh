#!/usr/bin/env bash
# 17-4PH 10–45 µm's rolling friction from its published angle of repose and apparent density
# (pour-17-4ph.toml says where they come from and what is assumed), two pours a setting: 6
# scrambled-Halton settings, then batches of 2, at most 20 pours. Resumable: run it again after
# an interruption. Record: record-17-4ph/ (posterior, batches, pours, answer).
#
#   nohup bash docs/study/calibration/calibrate-17-4ph.sh >/tmp/17-4ph.log 2>&1 &   # from the root
#
# SWEEP: the binary (default target/release/sweep); CAL_DIR: where the sweep directory goes;
# JOBS: pours at once (default 1).
set -euo pipefail
SWEEP=${SWEEP:-target/release/sweep}
DIR=docs/study/calibration
REC=$DIR/record-17-4ph
OUT=${CAL_DIR:-/tmp/calibration-study}/17-4ph
mkdir -p "$REC" "$(dirname "$OUT")"
status=0
"$SWEEP" calibrate "$DIR/pour-17-4ph.toml" --target "angle_of_repose=21.5±1.5" \
  --target "apparent_density=4.31±0.02" --first 6 --batch 2 --max 20 --repeats 2 \
  --jobs "${JOBS:-1}" --out "$OUT" || status=$?
"$SWEEP" report "$OUT" >"$REC/answer.txt" 2>&1 || true
for f in posterior.json calibration-batches.csv results.csv calibrated.toml calibrated-ranges.toml; do
  [ -f "$OUT/$f" ] && cp "$OUT/$f" "$REC/$f"
done
[ -f "$OUT/report/map-posterior-rolling_friction.png" ] && cp "$OUT/report/"*.png "$REC/" || true
# Each done pour: its rolling friction, seed's angle with SE, packing and CPU s.
python3 docs/study/calibration/pours.py "$OUT" rolling_friction >"$REC/pours.tsv"
exit $status
