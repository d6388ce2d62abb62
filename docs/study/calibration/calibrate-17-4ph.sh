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
python3 - "$OUT" >"$REC/pours.tsv" <<'PY'
import csv, json, os, sys
out = sys.argv[1]
print("index	rolling_friction	angle_deg	angle_se_deg	packing	apparent_density_g_cm3	cpu_s")
for r in csv.DictReader(open(os.path.join(out, "results.csv"))):
    path = os.path.join(out, "runs", r["hash"], "result.json")
    if r["status"] != "done" or not os.path.exists(path):
        continue
    j = json.load(open(path)); h = j["heap"]
    print(f"{r['index']}	{float(r['rolling_friction']):.4f}	{h['angle_deg']:.2f}	{h['angle_se_deg']:.2f}	{h['packing']:.3f}	{7.78 * h['packing']:.3f}	{j.get('cpu_time', 0):.0f}")
PY
exit $status
