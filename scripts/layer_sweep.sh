#!/usr/bin/env bash
# The report on real LIGGGHTS: 60 scrambled-Halton points of the thesis's 4-D space
# (sweeps/thesis-lds.toml, spaces of 20), then the report and screenshots of report.html at 800
# and 1,280 px (headless Chromium). Two LIGGGHTS processes at a time; resumable (run it again).
#   bash scripts/layer_sweep.sh [OUT_DIR] [N]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-runs/thesis-60}
n=${2:-60}
cargo build --release
target/release/sweep lds sweeps/thesis-lds.toml --step 20 --max "$n" --jobs 2 --out "$out" || true
target/release/sweep report "$out"
if command -v chromium > /dev/null; then
  for w in 800 1280; do
    chromium --headless --no-sandbox --disable-gpu --no-first-run --disable-background-networking \
      --screenshot="$out/report/screenshot-$w.png" --window-size="$w,6000" \
      "file://$(realpath "$out")/report/report.html" 2> /dev/null
  done
  echo "screenshots: $out/report/screenshot-{800,1280}.png"
fi
# Does every layer measure vary across the space by more than its own noise? The spread of
# each column over the done points, next to its typical per-point noise.
python3 - "$out/results.csv" <<'PY'
import csv, statistics, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["status"] == "done"]
def col(k): return [float(r[k]) for r in rows if r.get(k)]
print(f"{len(rows)} done points")
mfr = col("mfr"); n = col("mfr_particles")
se = [m / max(c, 1) ** 0.5 for m, c in zip(mfr, n)]
print(f"mfr: sd over points {statistics.pstdev(mfr):.4f}, median counting SE {statistics.median(se):.4f}")
for k in ["layer_cv", "covered_fraction", "roughness_d"]:
    v = col(k)
    if v: print(f"{k}: min {min(v):.3f} max {max(v):.3f} sd {statistics.pstdev(v):.3f}")
cvn = col("layer_cv_noise")
if cvn: print(f"layer_cv_noise: median {statistics.median(cvn):.3f}")
PY
