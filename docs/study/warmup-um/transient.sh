#!/usr/bin/env bash
# The conveyor's start-up transient at 20–40 µm: docs/study/recoater/transient.sh repeated on a
# real powder's scale. Each case runs with no warm-up and no precision stop to a fixed simulated
# time (converted to travel); transient.py finds where MSER cuts the block series and the bias
# after a warm-up w, in seconds, in heap gravity times √(H/g) and in travel.
#   bash docs/study/warmup-um/transient.sh [SWEEP_BIN]    (resumable: a finished case is kept)
# Environment: OUT (docs/study/warmup-um/runs), CASES (names to run, default all below, in
# order), BUDGET_S (3600: stop starting cases once the record's LIGGGHTS CPU reaches it).
# One LIGGGHTS at a time: `sweep run` runs one process.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
bin=${1:-sweep}
out=${OUT:-$here/runs}
budget=${BUDGET_S:-3600}
mkdir -p "$out"
# In the order run; the budget stops the list where it is spent.
# name | D (mm, or "ti64": sieved 15–45 µm, D10/D50/D90 20/31/42 µm) | gap mm | heap mm | v m/s |
# surface energy J/m² | friction | rolling friction | simulated time s | substrate (rough unless
# set: "powder" is a frozen bed of the powder itself)
# 35 µm: the issue's point (friction 0.3, restitution 0.4, ρ 4430, E 5 MPa); ti64: the powder and
# the point of sweeps/ti64-machine.toml (50 µm layer, 0.4 mm heap, μ 0.5, μ_r 0.1).
table="
D35-v0.08-h1-g0        0.035 0.1  1.0 0.08 0     0.3 0.1  0.16
D35-v0.08-h0.3-g0      0.035 0.1  0.3 0.08 0     0.3 0.1  0.09
D35-v0.2-h0.3-g0       0.035 0.1  0.3 0.2  0     0.3 0.1  0.09
D35-v0.08-h0.3-g1e-4   0.035 0.1  0.3 0.08 1e-4  0.3 0.1  0.09
D35-v0.02-h0.3-g0      0.035 0.1  0.3 0.02 0     0.3 0.1  0.15
ti64-v0.08-h0.4-g1e-4  ti64  0.05 0.4 0.08 1e-4  0.5 0.1  0.10
D35-v0.2-h1-g0         0.035 0.1  1.0 0.2  0     0.3 0.1  0.10
ti64-v0.2-h0.4-g1e-4   ti64  0.05 0.4 0.2  1e-4  0.5 0.1  0.10
ti64-v0.02-h0.4-g1e-4  ti64  0.05 0.4 0.02 1e-4  0.5 0.1  0.16
D35-v0.08-h1-g1e-4     0.035 0.1  1.0 0.08 1e-4  0.3 0.1  0.12
ti64-v0.08-h0.4-g1e-4-bed ti64 0.05 0.4 0.08 1e-4 0.5 0.1  0.10 powder
"
spent() {
  python3 - "$out" <<'PY'
import glob, json, sys
t = 0.0
for f in glob.glob(sys.argv[1] + "/*/result.json") + glob.glob(sys.argv[1] + "/*/failure.json") + glob.glob(sys.argv[1] + "/*/truncated"):
    r = json.load(open(f))
    r = r.get("measured") or r
    t += r.get("cpu_time") or 0.0
print(int(t))
PY
}
echo "$table" | while read -r name d gap heap v gamma mu mur time_s substrate; do
  [ -n "$name" ] || continue
  if [ -n "${CASES:-}" ] && ! [[ " $CASES " == *" $name "* ]]; then continue; fi
  case_dir=$out/$name
  [ -f "$case_dir/result.json" ] && continue
  # Stopped by hand at a shorter travel (the study's wall-clock): transient.py reads its log.
  [ -f "$case_dir/truncated" ] && continue
  [ -f "$case_dir/failure.json" ] && ! grep -q '"timed-out"' "$case_dir/failure.json" && continue
  used=$(spent)
  if [ "$used" -ge "$budget" ]; then echo "budget spent ($used CPU s): $name not run" >&2; continue; fi
  if [ "$d" = ti64 ]; then
    diameter=""; mean_um=24.4
    psd='[scene.size_distribution]
kind = "lognormal"
d10_um = 20.0
d50_um = 31.0
d90_um = 42.0
cut_um = [15.0, 45.0]
bins = 8'
  else
    diameter="diameter = { value = $d, unit = \"mm\" }"; mean_um=$(python3 -c "print($d*1e3)"); psd=""
  fi
  # The window cap counts after the least warm-up, 10 D (warmup_s = 0).
  cap=$(python3 -c "print(round($time_s*$v/($mean_um*1e-6) - 10))")
  cat > "$out/$name.toml" <<TOML
name = "warmup-um"
[parameters]
$diameter
gap = { value = $gap, unit = "mm" }
blade_speed = { value = $v, unit = "m/s" }
heap_height = { value = $heap, unit = "mm" }
density = { value = 4430, unit = "kg/m3" }
surface_energy = { value = $gamma, unit = "J/m2" }
restitution = 0.4
rolling_friction = $mur
youngs_modulus = { value = 5, unit = "MPa" }
friction = { lo = $(python3 -c "print($mu-0.05)"), hi = $(python3 -c "print($mu+0.05)") }   # its middle: a sweep file needs one swept parameter
[scene]
layout = "conveyor"
substrate = "${substrate:-rough}"
warmup_s = 0.0
mfr_rel_se = 0.0
mfr_abs_se = 0.0
window_cap_diameters = $cap
$psd
[run]
timeout_s = 3600
TOML
  echo "$name: $time_s s, $cap D of travel after 10 D ($used CPU s spent)" >&2
  "$bin" run "$out/$name.toml" --out "$case_dir" --json > /dev/null || true
done
python3 "$here/transient.py" "$out"
