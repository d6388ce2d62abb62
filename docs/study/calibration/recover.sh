#!/usr/bin/env bash
# The recovery of a known sliding/rolling friction pair from two targets on LIGGGHTS
# (docs/study/calibration.md, "A known pair from two targets"): pour-friction-rolling.toml (2 mm
# steel spheres, sliding 0.1–0.5 and rolling 0.1–0.3 free) poured at the truth 0.3/0.2 with four
# seeds; the mean angle of repose and the mean apparent density (the heap's packing × 7.98 g/cm³),
# each ± its SE between those seeds, are the targets of a calibration with two pours (seeds) a
# setting. Resumable: a recorded truth pour is not poured again, and the calibration goes on
# where its directory stands. Record: record-recover/ (truth pours, targets, posterior, pours).
#
#   nohup bash docs/study/calibration/recover.sh >/tmp/recover.log 2>&1 &   # from the root
#
# SWEEP: the binary (default target/release/sweep); CAL_DIR: where the sweep directory goes.
set -euo pipefail
SWEEP=${SWEEP:-target/release/sweep}
DIR=docs/study/calibration
REC=$DIR/record-recover
OUT=${CAL_DIR:-/tmp/calibration-study}/recover
mkdir -p "$REC" "$(dirname "$OUT")"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
for seed in 1 2 3 4; do
  rec="$REC/truth-s$seed.json"
  [ -s "$rec" ] && continue
  sed -e "s/^seed = .*/seed = $seed/" "$DIR/pour-friction-rolling.toml" >"$WORK/truth.toml"
  echo "$(date -u +%H:%M:%S) truth pour, seed $seed"
  "$SWEEP" run "$WORK/truth.toml" --set friction=0.3,rolling_friction=0.2 --json >"$rec.part"
  mv "$rec.part" "$rec"
done
# The targets: each mean ± its SE between the seeds (SD / √n).
python3 - "$REC" >"$REC/targets.txt" <<'PY'
import glob, json, statistics, sys
heaps = [json.load(open(f))["heap"] for f in sorted(glob.glob(sys.argv[1] + "/truth-s*.json"))]
a = [h["angle_deg"] for h in heaps]
d = [7.98 * h["packing"] for h in heaps]
se = lambda v: statistics.stdev(v) / len(v) ** 0.5
print(f"angle_of_repose={statistics.mean(a):.2f}±{se(a):.2f}")
print(f"apparent_density={statistics.mean(d):.3f}±{max(se(d), 0.005):.3f}")
PY
cat "$REC/targets.txt"
args=()
while read -r t; do args+=(--target "$t"); done <"$REC/targets.txt"
status=0
"$SWEEP" calibrate "$DIR/pour-friction-rolling.toml" "${args[@]}" \
  --first 10 --batch 2 --max 36 --repeats 2 --jobs 1 --out "$OUT" || status=$?
"$SWEEP" report "$OUT" >"$REC/answer.txt" 2>&1 || true
for f in posterior.json calibration-batches.csv results.csv calibrated.toml calibrated-ranges.toml; do
  [ -f "$OUT/$f" ] && cp "$OUT/$f" "$REC/$f"
done
# Each done pour: its sliding and rolling friction, seed, angle with SE, packing and CPU s.
python3 docs/study/calibration/pours.py "$OUT" friction rolling_friction >"$REC/pours.tsv"
exit $status
