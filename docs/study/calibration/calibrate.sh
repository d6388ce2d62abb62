#!/usr/bin/env bash
# The calibration recoveries of docs/study/calibration.md on LIGGGHTS, one pour at a time,
# against the angle of repose the pour gave at friction 0.3, rolling friction 0.2
# (docs/study/pour/pour.tsv: 26.55 ± 0.73°): rolling friction alone (`rolling`), or sliding and
# rolling friction together (`friction-rolling`); or the surface energy of Ti-6Al-4V 15–45 µm
# against the angle its pour gave at 0.01 mJ/m² (`ti64-surface-energy`: that target pour runs
# first, once, and is kept in the record as target.json); or the surface energy of 316L against
# the angle of repose a public flowability dataset records for it, 28.2° (`316l-surface-energy`,
# pour-316l.toml says where it comes from and what is assumed), or its rolling friction against
# the same angle (`316l-rolling`). Resumable: run it again after an
# interruption and it goes on where the directory stands. Its record (posterior, batches,
# pours) is copied to docs/study/calibration/record/ (record-friction-rolling/,
# record-ti64-surface-energy/) after each run.
#
#   bash docs/study/calibration/calibrate.sh                    # from the repository's root
#   bash docs/study/calibration/calibrate.sh friction-rolling
#   bash docs/study/calibration/calibrate.sh ti64-surface-energy
#   bash docs/study/calibration/calibrate.sh 316l-surface-energy
#   bash docs/study/calibration/calibrate.sh 316l-rolling
#
# These studies ran one pour per setting (`--repeats 1`), before repeats measured the scatter
# between seeds.
#
# SWEEP: the binary (default target/release/sweep); CAL_DIR: the sweep directory.
set -euo pipefail
SWEEP=${SWEEP:-target/release/sweep}
STUDY=${1:-rolling}
TARGET=26.55±0.73
case "$STUDY" in
  rolling) REC=docs/study/calibration/record; FIRST=8; MAX=20; FILE=pour-rolling ;;
  friction-rolling) REC=docs/study/calibration/record-friction-rolling; FIRST=10; MAX=40; FILE=pour-friction-rolling ;;
  ti64-surface-energy) REC=docs/study/calibration/record-ti64-surface-energy; FIRST=4; MAX=12; FILE=pour-ti64 ;;
  316l-surface-energy) REC=docs/study/calibration/record-316l-surface-energy; FIRST=4; MAX=12; FILE=pour-316l; TARGET=28.2±1.0 ;;
  316l-rolling) REC=docs/study/calibration/record-316l-rolling; FIRST=4; MAX=12; FILE=pour-316l-rolling; TARGET=28.2±1.0 ;;
  *) echo "calibrate.sh: unknown study $STUDY: expected rolling, friction-rolling, ti64-surface-energy, 316l-surface-energy or 316l-rolling" >&2; exit 2 ;;
esac
OUT=${CAL_DIR:-/tmp/calibration-study}/pour-$STUDY
mkdir -p "$(dirname "$OUT")" "$REC"
if [ "$STUDY" = ti64-surface-energy ]; then
  # The target: the same pour at 0.01 mJ/m², its angle with its own SE as the measurement's SD.
  if [ ! -s "$REC/target.json" ]; then
    "$SWEEP" run "docs/study/calibration/$FILE.toml" --set surface_energy=1e-5 --json >"$REC/target.json.part"
    mv "$REC/target.json.part" "$REC/target.json"
  fi
  TARGET=$(python3 -c 'import json,sys; h=json.load(open(sys.argv[1]))["heap"]; print("%.2f±%.2f" % (h["angle_deg"], h["angle_se_deg"]))' "$REC/target.json")
fi
status=0
"$SWEEP" calibrate "docs/study/calibration/$FILE.toml" \
  --target "angle_of_repose=$TARGET" --first "$FIRST" --batch 2 --max "$MAX" --repeats 1 --jobs 1 --out "$OUT" || status=$?
"$SWEEP" report "$OUT" >"$REC/answer.txt" 2>&1 || true
for f in posterior.json calibration-batches.csv results.csv calibrated.toml calibrated-ranges.toml; do
  [ -f "$OUT/$f" ] && cp "$OUT/$f" "$REC/$f"
done
"$SWEEP" status "$OUT" >"$REC/status.txt" 2>&1 || true
# Each done pour: its sliding and rolling friction, surface energy (mJ/m²), angle with SE, packing and
# CPU seconds, in run order.
python3 docs/study/calibration/pours.py "$OUT" friction rolling_friction surface_energy >"$REC/pours.tsv"
exit $status
