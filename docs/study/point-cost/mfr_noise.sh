#!/usr/bin/env bash
# Seed-to-seed spread of one point's MFR against its cost, for scene sizes: the same point
# (default D = 3 mm, gap = 5 mm, μ = 0.3, v = 1.6 m/s) run with several pile seeds for each
# (window, depth) in diameters. Prints a Markdown table (BENCHMARKS.md "MFR noise").
#   SIZES="20 6,40 6" bash docs/study/point-cost/mfr_noise.sh [D_mm] [gap_mm] [seeds]   (SIZES: "window depth,...")
set -euo pipefail
cd "$(dirname "$0")/../../.."
d=${1:-3}; gap=${2:-5}; seeds=${3:-6}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
echo "| window (D) | depth (D) | particles | MFR mean | MFR sd | sd/mean | counted | CPU s/run |"
echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
IFS=, read -r -a sizes <<< "${SIZES:-20 6,40 6,20 12}"
for size in "${sizes[@]}"; do
  set -- $size
  for seed in $(seq 1 "$seeds"); do
    cat > "$tmp/s.toml" <<TOML
name = "noise"
[parameters]
gap = { lo = 0.5, hi = 10.0, unit = "mm" }
diameter = $d
friction = 0.3
blade_speed = 1.6
[scene]
window_diameters = $1
depth_diameters = $2
seed = $seed
TOML
    /usr/bin/time -f "%U" -o "$tmp/cpu.$seed" target/release/sweep run "$tmp/s.toml" --set "gap=$gap" --json > "$tmp/r.$seed.json"
  done
  python3 - "$tmp" "$seeds" "$1" "$2" <<'PY'
import json, statistics, sys
tmp, n, window, depth = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
rs = [json.load(open(f"{tmp}/r.{i}.json")) for i in range(1, n + 1)]
cpu = [float(open(f"{tmp}/cpu.{i}").read()) for i in range(1, n + 1)]
m = [r["mfr"] for r in rs]
mean, sd = statistics.mean(m), statistics.pstdev(m)
counted = statistics.mean(r["mfr_particles"] for r in rs)
print(f"| {window} | {depth} | {rs[0]['particles']} | {mean:.4f} | {sd:.4f} | {sd/mean:.1%} | {counted:.0f} | {statistics.mean(cpu):.1f} |")
PY
done
