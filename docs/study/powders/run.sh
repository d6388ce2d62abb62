#!/bin/bash
# The real-powder study (docs/study/powders.md): each point once, its result.json kept in
# points/NAME.json; a point already there is skipped, so the script resumes where it stopped.
#   docs/study/powders/run.sh [path/to/sweep]      (default: target/release/sweep)
set -u
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
sweep=${1:-$repo/target/release/sweep}
mkdir -p "$here/points"
point() {  # NAME SWEEPFILE SET
  local out="$here/points/$1.json"
  [ -s "$out" ] && return
  echo "$(date -u +%H:%M:%S) $1: $3" >&2
  "$sweep" run "$2" --set "$3" --json > "$out.tmp" 2> "$here/points/$1.err"
  mv "$out.tmp" "$out"
}
ti=$repo/sweeps/ti64-machine.toml
one=$here/ti64-35um.toml
# Cohesion against none: the machine example at 0.1 m/s, the 35 µm point at a 100 µm gap.
point ti64-v0.1-coh "$ti" blade_speed=0.1,surface_energy=1e-4
point ti64-v0.1-dry "$ti" blade_speed=0.1,surface_energy=0
point d35-gap0.1-coh "$one" gap=0.1,surface_energy=1e-4
point d35-gap0.1-dry "$one" gap=0.1,surface_energy=0
# Finer at the same gap/D50 spreads worse once cohesive: D50 × 2/3 with the gap and heap scaled.
point d23-gap0.067-coh "$one" gap=0.0667,diameter=0.0233,heap_height=0.667,surface_energy=1e-4
point d23-gap0.067-dry "$one" gap=0.0667,diameter=0.0233,heap_height=0.667,surface_energy=0
# Shaheen et al. 2021 on our scene: the corners and centre of sliding × rolling friction, at
# 100, 50 and then 10 mm/s.
sh=$here/shaheen.toml
for v in 0.1 0.05 0.01; do
  for mu in "0.05 0.005" "0.05 0.4" "0.5 0.005" "0.5 0.4" "0.275 0.2"; do
    set -- $mu
    point "shaheen-v$v-mu$1-mur$2" "$sh" "blade_speed=$v,friction=$1,rolling_friction=$2"
  done
done
# The cohesive machine point on a bed of the powder.
point ti64-bed-v0.1-coh "$here/ti64-bed.toml" blade_speed=0.1,surface_energy=1e-4
