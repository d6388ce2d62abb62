#!/usr/bin/env bash
# The conveyor's start-up transient against blade travel, at a fixed heap in millimetres.
# Each point runs with no precision stop to a fixed travel; transient.py finds where MSER cuts
# the block series and says it in travel (mm, D, heap lengths) and in time.
#   bash docs/study/recoater/transient.sh [SWEEP_BIN]      (resumable: a finished case is kept)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
bin=${1:-sweep}
out=$here/transient-runs
mkdir -p "$out"
travel_mm=${TRAVEL_MM:-200}
for d in 3 2 1 0.5; do
  for v in 1.4 0.4 0.1; do
    # The finest powder at the slowest speed costs an hour: left out.
    if [ "$d" = 0.5 ] && [ "$v" = 0.1 ]; then continue; fi
    case_dir=$out/D$d-v$v
    # Done, or failed for a reason of its own (a timeout is the machine's, not the point's).
    [ -f "$case_dir/result.json" ] && continue
    [ -f "$case_dir/failure.json" ] && ! grep -q '"timed-out"' "$case_dir/failure.json" && continue
    gap=$(python3 -c "print(2.5*$d)")
    cap=$(python3 -c "print($travel_mm/$d)")
    cat > "$out/D$d-v$v.toml" <<TOML
name = "transient"
[parameters]
diameter = { value = $d, unit = "mm" }
gap = { value = $gap, unit = "mm" }
blade_speed = { value = $v, unit = "m/s" }
heap_height = { value = 20, unit = "mm" }
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
    echo "D $d mm, v $v m/s: $cap D of travel" >&2
    "$bin" run "$out/D$d-v$v.toml" --out "$case_dir" --json > /dev/null || true
  done
done
python3 "$here/transient.py" "$out"
