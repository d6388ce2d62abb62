#!/usr/bin/env bash
# "A pass is its crossing" (issue 67): each cut of a layers pass measured alone against the
# baseline, a whole point each (it stops once steady), one LIGGGHTS run at a time:
#   machine — sweeps/ti64-layers.toml at 50 µm and 0.1 m/s (the shipped file, no hand-set key);
#   PS1     — sweeps/layers-gaboriault.toml at 0.1 m/s, Gaboriault et al.'s PS1 (the file's own
#             friction 0.20, rolling 0.10 and 4.667e-4 J/m², docs/study/layers/twenty.sh);
#   single  — sweeps/ti64-machine.toml's single layer at 0.08 m/s, for the cost ratio;
#   machine30, single30 — the layers point at 30 µm layers (0.1 m/s) and the single layer at a
#             30 µm gap and 0.1 m/s, the ratio at the thin layer;
#   machine-slow, single-slow — the same at 50 µm and 0.05 m/s, the ratio at the slow blade;
#   machine30-fast — the layers point at 30 µm and 0.2 m/s (the machine lattice's fastest corner);
#   machine-plate80, machine-plate160 — the machine point on a plate of 80 or 160 mean
#             diameters (`plate_diameters`; the shipped 40 D), its numerical bound.
# The binary is $SWEEP (one built per cut, e.g. /tmp/sweep-A); LABEL names it in the records;
# SEED=n runs every scene at another seed (`seed = n`, the label's records -seedn); KEY="name =
# value" adds that [scene] key to the layers files (a cut that is a key: name it in LABEL).
# Each run keeps its directory under runs/cuts/<label>-<scene>/, so an interrupted study goes on
# from each point's last pass (run it again); the passes' records (pass.k.json: clocks) go to
# record/cuts/<label>-<scene>/ and the result to record/cuts/<label>-<scene>.json.
#   SWEEP=/tmp/sweep-base nice bash docs/study/layers/cuts.sh base machine PS1
set -euo pipefail
cd "$(dirname "$0")/../../.."
sweep=${SWEEP:-target/release/sweep}
label=$1
shift
out=docs/study/layers/record/cuts
mkdir -p "$out" runs/cuts
# The shipped files, with a timeout long enough for a machine shared with other work.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
seed=${SEED:-}
for f in ti64-layers layers-gaboriault ti64-machine; do
  if grep -q '^timeout_s = ' "sweeps/$f.toml"; then
    sed -e 's/^timeout_s = .*$/timeout_s = 40000/' "sweeps/$f.toml" > "$tmp/$f.toml"
  else
    sed -e 's/^\[scene\]$/[run]\ntimeout_s = 40000\n\n[scene]/' "sweeps/$f.toml" > "$tmp/$f.toml"
  fi
  grep -q '^timeout_s = 40000$' "$tmp/$f.toml"
  if [ -n "${KEY:-}" ] && [ "$f" != ti64-machine ]; then
    sed -i -e "s/^\[scene\]$/[scene]\n$KEY/" "$tmp/$f.toml"
    grep -qx "$KEY" "$tmp/$f.toml"
  fi
  if [ -n "$seed" ]; then
    sed -i -e "s/^\[scene\]$/[scene]\nseed = $seed/" "$tmp/$f.toml"
    grep -q "^seed = $seed$" "$tmp/$f.toml"
  fi
done
for scene in "$@"; do
  case $scene in
    machine) file=ti64-layers set=layer_thickness=0.05,blade_speed=0.1 ;;
    machine-plate*) file=ti64-layers set=layer_thickness=0.05,blade_speed=0.1
      plate=${scene#machine-plate}
      sed -e "s/^\[scene\]$/[scene]\nplate_diameters = $plate.0/" "$tmp/$file.toml" > "$tmp/$scene.toml"
      grep -q "^plate_diameters = $plate.0$" "$tmp/$scene.toml"
      file=$scene ;;
    machine30) file=ti64-layers set=layer_thickness=0.03,blade_speed=0.1 ;;
    machine-slow) file=ti64-layers set=layer_thickness=0.05,blade_speed=0.05 ;;
    machine30-fast) file=ti64-layers set=layer_thickness=0.03,blade_speed=0.2 ;;
    single30) file=ti64-machine set=gap=0.03,blade_speed=0.1 ;;
    single-slow) file=ti64-machine set=blade_speed=0.05 ;;
    PS1) file=layers-gaboriault set=blade_speed=0.1,friction=0.20,rolling_friction=0.10,surface_energy=4.667e-4 ;;
    single) file=ti64-machine set=blade_speed=0.08 ;;
    *) echo "unknown scene $scene" >&2; exit 2 ;;
  esac
  name=$label-$scene${seed:+-seed$seed}
  [ -s "$out/$name.json" ] && { echo "$name: recorded"; continue; }
  dir=runs/cuts/$name
  ( while sleep 60; do mkdir -p "$out/$name"; cp "$dir"/pass.*.json "$out/$name/" 2>/dev/null || true; done ) &
  copier=$!
  "$sweep" run "$tmp/$file.toml" --json --out "$dir" --set "$set" > "$out/$name.json.part" 2> "$out/$name.err" || true
  kill $copier 2>/dev/null || true
  mkdir -p "$out/$name"; cp "$dir"/pass.*.json "$out/$name/" 2>/dev/null || true
  if grep -q '"cpu_time"' "$out/$name.json.part"; then
    mv "$out/$name.json.part" "$out/$name.json"
  else
    rm -f "$out/$name.json.part"   # interrupted: run again to go on from its last pass
  fi
done
