#!/usr/bin/env bash
# The calibration recoveries of docs/study/calibration.md on LIGGGHTS, one pour at a time,
# against the angle of repose the pour gave at friction 0.3, rolling friction 0.2
# (docs/study/pour/pour.tsv: 26.55 ± 0.73°): rolling friction alone (`rolling`), or sliding and
# rolling friction together (`friction-rolling`). Resumable: run it again after an
# interruption and it goes on where the directory stands. Its record (posterior, batches,
# pours) is copied to docs/study/calibration/record/ (record-friction-rolling/) after each run.
#
#   bash docs/study/calibration/calibrate.sh                    # from the repository's root
#   bash docs/study/calibration/calibrate.sh friction-rolling
#
# SWEEP: the binary (default target/release/sweep); CAL_DIR: the sweep directory.
set -euo pipefail
SWEEP=${SWEEP:-target/release/sweep}
STUDY=${1:-rolling}
case "$STUDY" in
  rolling) REC=docs/study/calibration/record; FIRST=8; MAX=20 ;;
  friction-rolling) REC=docs/study/calibration/record-friction-rolling; FIRST=10; MAX=40 ;;
  *) echo "calibrate.sh: unknown study $STUDY: expected rolling or friction-rolling" >&2; exit 2 ;;
esac
OUT=${CAL_DIR:-/tmp/calibration-study}/pour-$STUDY
mkdir -p "$(dirname "$OUT")" "$REC"
status=0
"$SWEEP" calibrate "docs/study/calibration/pour-$STUDY.toml" \
  --target angle_of_repose=26.55±0.73 --first "$FIRST" --batch 2 --max "$MAX" --jobs 1 --out "$OUT" || status=$?
"$SWEEP" report "$OUT" >"$REC/answer.txt" 2>&1 || true
for f in posterior.json calibration-batches.csv results.csv calibrated.toml calibrated-ranges.toml; do
  [ -f "$OUT/$f" ] && cp "$OUT/$f" "$REC/$f"
done
"$SWEEP" status "$OUT" >"$REC/status.txt" 2>&1 || true
# Each done pour: its sliding and rolling friction, angle with SE, packing and CPU seconds, in run order.
python3 - "$OUT" >"$REC/pours.tsv" <<'PY'
import csv, json, os, sys
out = sys.argv[1]
print("index	friction	rolling_friction	angle_deg	angle_se_deg	packing	cpu_s")
for r in csv.DictReader(open(os.path.join(out, "results.csv"))):
    path = os.path.join(out, "runs", r["hash"], "result.json")
    if r["status"] != "done" or not os.path.exists(path):
        continue
    j = json.load(open(path)); h = j["heap"]
    print(f"{r['index']}	{j['parameters']['friction']:.4f}	{float(r['rolling_friction']):.4f}	{h['angle_deg']:.2f}	{h['angle_se_deg']:.2f}	{h['packing']:.3f}	{j.get('cpu_time', 0):.0f}")
PY
exit $status
