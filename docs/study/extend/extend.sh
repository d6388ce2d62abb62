#!/usr/bin/env bash
# What extending a finished sweep saves against running it again at the tighter target.
#   bash docs/study/extend/extend.sh SWEEP_FILE OUT SHARE
# 1. the sweep as it is (`sweep lds`, its own precision): OUT/first
# 2. a copy of it extended to SE = SHARE × the median SE of its points: OUT/extended
# 3. the same points run from rest to that SE: OUT/fresh
# then python3 docs/study/extend/summary.py OUT. Each step is skipped when its directory is
# complete, so the script resumes.
set -euo pipefail
file=$1 out=$2 share=$3
mkdir -p "$out"
jobs=${JOBS:-2}
[ -f "$out/first/results.csv" ] || sweep lds "$file" --out "$out/first" -q --jobs "$jobs" || true
target=$(python3 - "$out/first" "$share" <<'PY'
import csv, sys, statistics
rows = [r for r in csv.DictReader(open(sys.argv[1] + "/results.csv")) if r["status"] == "done"]
print(float(sys.argv[2]) * statistics.median(float(r["mfr_se"]) for r in rows))
PY
)
echo "target SE $target"
if [ ! -f "$out/extended.done" ]; then
  rm -rf "$out/extended" && cp -a "$out/first" "$out/extended"
  sweep extend "$out/extended" --se "$target" --jobs "$jobs" -q && touch "$out/extended.done"
fi
if [ ! -f "$out/fresh/results.csv" ]; then
  python3 - "$file" "$out/fresh.toml" "$target" <<'PY'
import sys
text, target = open(sys.argv[1]).read(), sys.argv[3]
lines = f"mfr_rel_se = 0.0\nmfr_abs_se = {target}\n"
text = text.replace("[scene]\n", "[scene]\n" + lines, 1) if "\n[scene]\n" in text else text + "\n[scene]\n" + lines
open(sys.argv[2], "w").write(text)
PY
  sweep lds "$out/fresh.toml" --out "$out/fresh" -q --jobs "$jobs" || true
fi
python3 "$(dirname "$0")/summary.py" "$out"
