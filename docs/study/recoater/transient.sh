#!/usr/bin/env bash
# The conveyor's start-up transient against blade travel, at a fixed heap in millimetres.
# Each point runs with no precision stop to a fixed travel; transient.py finds where MSER cuts
# the block series and says it in travel (mm, D, heap lengths) and in time.
#   bash docs/study/recoater/transient.sh [SWEEP_BIN]      (resumable: a finished case is kept)
# Environment: TRAVEL_MM (200), OUT (transient-runs), DIAMETERS ("3 2 1 0.5"), SPEEDS ("1.4 0.4 0.1"),
# HEAP_MM (20: the held heap's height above the blade tip; another height names its cases D*-v*-h*).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
bin=${1:-sweep}
out=${OUT:-$here/transient-runs}
mkdir -p "$out"
travel_mm=${TRAVEL_MM:-200}
for d in ${DIAMETERS:-3 2 1 0.5}; do
  for v in ${SPEEDS:-1.4 0.4 0.1}; do
    # The finest powder at the slowest speed costs an hour: left out.
    if [ "$d" = 0.5 ] && [ "$v" = 0.1 ]; then continue; fi
    heap=${HEAP_MM:-20}
    name=D$d-v$v; [ "$heap" = 20 ] || name=$name-h$heap
    case_dir=$out/$name
    # Done, or failed for a reason of its own (a timeout is the machine's, not the point's).
    [ -f "$case_dir/result.json" ] && continue
    [ -f "$case_dir/failure.json" ] && ! grep -q '"timed-out"' "$case_dir/failure.json" && continue
    gap=$(python3 -c "print(2.5*$d)")
    # The window cap counts after the least warm-up, 10 D.
    cap=$(python3 -c "print($travel_mm/$d - 10)")
    cat > "$out/$name.toml" <<TOML
name = "transient"
[parameters]
diameter = { value = $d, unit = "mm" }
gap = { value = $gap, unit = "mm" }
blade_speed = { value = $v, unit = "m/s" }
heap_height = { value = $heap, unit = "mm" }
friction = { lo = 0.1, hi = 0.3 }   # its middle, 0.2: a sweep file needs one swept parameter
[scene]
layout = "conveyor"
warmup_s = 0.0
mfr_rel_se = 0.0
mfr_abs_se = 0.0
window_cap_diameters = $cap
[run]
timeout_s = 14400
TOML
    echo "D $d mm, v $v m/s, heap $heap mm: $cap D of travel" >&2
    "$bin" run "$out/$name.toml" --out "$case_dir" --json > /dev/null || true
  done
done
python3 "$here/transient.py" "$out"
