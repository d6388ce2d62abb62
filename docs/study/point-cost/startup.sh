#!/usr/bin/env bash
# Does the conveyor's start-up overshoot come from how the heap starts? The thesis-speed point
# D 2 mm, gap 5 mm, 1.4 m/s, heap 20 mm, run with no warm-up and no precision stop to 700 mm of
# travel, 8 particle seeds, three ways (BENCHMARKS.md "Where a point's CPU goes"):
#   base    the deck as it is: the heap inserted loose (about 0.17 of its box) as the substrate starts
#   settle  the heap falls at rest for 2,500 steps (0.088 s) before the substrate moves
#   ramp    the substrate's speed raised in five steps of 300 (1/6 ... 5/6 of it, 0.053 s)
# then startup.py prints the mean MFR of the seeds by 4 blocks (40 mm, 0.029 s) from the start
# of full speed.
#   bash docs/study/point-cost/startup.sh [WORK]      (resumable: a finished run is kept)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
bin=${SWEEP_BIN:-$here/../../../target/release/sweep}
work=${1:-/tmp/startup-study}
mkdir -p "$work"
template=$here/../../../templates/conveyor.liggghts.tera
python3 "$here/startup.py" variants "$template" "$work"
for v in base settle ramp; do
  for seed in 1 2 3 4 5 6 7 8; do
    run=$work/$v-s$seed
    [ -f "$run/result.json" ] || [ -f "$run/failure.json" ] && continue
    cat > "$work/$v-s$seed.toml" <<TOML
name = "startup"
[parameters]
diameter = { value = 2, unit = "mm" }
gap = { value = 5, unit = "mm" }
blade_speed = { value = 1.4, unit = "m/s" }
heap_height = { value = 20, unit = "mm" }
friction = { lo = 0.1, hi = 0.3 }   # its middle, 0.2: a sweep file needs one swept parameter
[scene]
template = "$work/$v.tera"
seed = $seed
layout = "conveyor"
warmup_s = 0.0
mfr_rel_se = 0.0
mfr_abs_se = 0.0
window_cap_diameters = 340
TOML
    # Without a warm-up most runs fail as unsteady; their block series is what is read.
    "$bin" run "$work/$v-s$seed.toml" --out "$run" --json > /dev/null 2>&1 || true
  done
done
python3 "$here/startup.py" table "$work"
