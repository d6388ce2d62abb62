#!/usr/bin/env bash
# The scene's convergence study (BENCHMARKS.md "Scene convergence"): every numerical choice
# of the scene halved and doubled, one at a time,
# on 8 points of the thesis 4-D space (a seeded LDS draw of 6, plus the corners D 1 mm / gap 5 mm
# and D 3 mm / gap 4 mm) with 3 pile seeds each; then a 24-point LDS draw on the new scene and on
# the first one (layout "thesis", no rolling friction) for the steadiness and cost comparison.
# One row per run is appended to OUT (TSV), so an interrupted study resumes where it stopped;
# docs/study/scene-convergence/scene_study.py turns it into the tables.
#   bash docs/study/scene-convergence/scene_study.sh [OUT.tsv] [VARIANTS...]      (default: every variant)
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=${1:-scene_study.tsv}; shift || true
bin=${SWEEP_BIN:-$PWD/target/release/sweep}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# variant name → scene settings (TOML lines under [scene]) and extra parameters.
declare -A scene=(
  [base]=""
  [window/2]="window_diameters = 20.0"        [window*2]="window_diameters = 80.0"
  [start/2]="window_start_diameters = 15.0"   [start*2]="window_start_diameters = 60.0"
  [supply/2]="supply_factor = 0.5"            [supply*2]="supply_factor = 2.0"
  [rest/2]="rest_speed = 0.005"               [rest*2]="rest_speed = 0.02"
  [depth/2]="depth_diameters = 3.0"           [depth*2]="depth_diameters = 12.0"
  [dt/2]="rayleigh_fraction = 0.1"            [dt*2]="rayleigh_fraction = 0.4"
  [lds24-new]=""
  [lds24-old]='layout = "thesis"'
)
order=(base lds24-new lds24-old window/2 window*2 start/2 start*2 supply/2 supply*2 rest/2 rest*2 depth/2 depth*2 dt/2 dt*2)
[ $# -gt 0 ] && order=("$@")

# The 8 study points (friction, D mm, gap mm, v m/s): LDS seed 14 of the thesis space, 6 points,
# and the two corners at mid friction and speed.
study_points=$("$bin" points sweeps/thesis-lds.toml --lds 6 | tail -n +2)
study_points+=$'\n'"0.2,1.0,5.0,1.4"$'\n'"0.2,3.0,4.0,1.4"
lds24_points=$("$bin" points sweeps/thesis-lds.toml --lds 24 | tail -n +2)

[ -f "$out" ] || printf 'variant\tpoint\tseed\tfriction\tdiameter\tgap\tblade_speed\tstatus\tmfr\tmfr_flux\tmfr_particles\tsteady_p\tmfr_windows\tvx\tparticles\tsettle_steps\tsteps\tcpu_s\n' > "$out"

one() { # variant point_index seed friction D gap v
  local v=$1 i=$2 seed=$3 mu=$4 d=$5 gap=$6 speed=$7
  if grep -qP "^\Q$v\E\t$i\t$seed\t" "$out"; then return; fi
  local dir="$work/run.${v//\//_}.$i.$seed" toml="$work/s.${v//\//_}.$i.$seed.toml"
  local rolling=""
  [ "$v" = lds24-old ] && rolling="rolling_friction = 0.0"
  cat > "$toml" <<TOML
name = "study"
[parameters]
friction = { lo = 0.0, hi = 1.0 }
diameter = { lo = 0.5, hi = 5.0, unit = "mm" }
gap = { lo = 0.5, hi = 10.0, unit = "mm" }
blade_speed = { lo = 0.5, hi = 3.0, unit = "m/s" }
$rolling
[scene]
seed = $seed
$SCENE_LINES
TOML
  /usr/bin/time -f "%U %S" -o "$dir.time" "$bin" run "$toml" --set "friction=$mu,diameter=$d,gap=$gap,blade_speed=$speed" \
    --out "$dir" --json > /dev/null 2>&1 || true
  local cpu
  cpu=$(awk 'END { print $1 + $2 }' "$dir.time")
  python3 - "$dir" "$v" "$i" "$seed" "$mu" "$d" "$gap" "$speed" "$cpu" >> "$out" <<'PY'
import json, os, sys
dir, v, i, seed, mu, d, gap, speed, cpu = sys.argv[1:]
status, r = "failed:unknown", {}
if os.path.exists(f"{dir}/result.json"):
    status, r = "done", json.load(open(f"{dir}/result.json"))
elif os.path.exists(f"{dir}/failure.json"):
    f = json.load(open(f"{dir}/failure.json"))
    status, r = "failed:" + f["class"], f.get("measured") or {}
g = lambda k: r.get(k, "")
print("\t".join(str(x) for x in [v, i, seed, mu, d, gap, speed, status, g("mfr"), g("mfr_flux"),
      g("mfr_particles"), g("steady_p"), json.dumps(g("mfr_windows")), json.dumps(g("vx")),
      g("particles"), g("settle_steps"), g("steps"), cpu]))
PY
  rm -rf "$dir"
}
export -f one
export out bin work
for v in "${order[@]}"; do
  if [[ $v == lds24-* ]]; then points=$lds24_points; seeds=1; else points=$study_points; seeds="1 2 3"; fi
  jobs=()
  i=0
  while IFS=, read -r mu d gap speed; do
    i=$((i + 1))
    for seed in $seeds; do jobs+=("$v|$i|$seed|$mu|$d|$gap|$speed"); done
  done <<< "$points"
  # Bash cannot export an associative array: the variant's settings go through the environment.
  printf '%s\n' "${jobs[@]}" | SCENE_LINES="${scene[$v]}" parallel -j "${JOBS:-2}" --colsep '\|' \
    one {1} {2} {3} {4} {5} {6} {7}
  echo "scene_study: $v done" >&2
done
