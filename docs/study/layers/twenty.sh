#!/usr/bin/env bash
# Gaboriault et al. 2025's 20 measured layers (issue: the experiment in step): PS1–PS3 on
# sweeps/layers-gaboriault.toml at 21 passes (the baseline pass and their layers 1–20, every pass
# run: least_layers = layers = 21), optionally at another plate length (PLATE=diameters). Each
# point runs pass by pass in runs/twenty/<label>/: an interrupted study goes on from each point's
# last pass (run it again), and the passes' records (pass.k.json: clocks) are copied to
# record/twenty/<label>/ as they finish, the result to record/twenty-<label>.json at the end.
# FREEZE=diameters holds the loose bed still that deep under the top surface (label -freezeN);
# TAG=word adds -word to the label (a run of a changed deck beside a recorded one).
# KEY="name = value" adds that [scene] key (a numerical choice halved or doubled: label it with
# TAG); PASSES=n runs n passes, not 21 (their layers 1 to n − 1).
#   nice bash docs/study/layers/twenty.sh [PS1|PS2|PS3]
#   FREEZE=4 PASSES=11 KEY="depth_diameters = 12" TAG=bury-depth12 nice bash docs/study/layers/twenty.sh PS1
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
plate=${PLATE:-24}
freeze=${FREEZE:-0}
passes=${PASSES:-21}
mkdir -p "$out/twenty" runs/twenty
cases="PS1 0.20 0.10 3.5e-4
PS2 0.20 0.20 2.5e-4
PS3 0.40 0.36 8.0e-5"
want=${1:-}
toml=$(mktemp --suffix=.toml)
# A point's timeout bounds all its passes' wall time together, across resumes: 21 passes beside
# other work take far longer than the file's single point.
sed -e "s/^layers = [0-9]*$/layers = $passes\nleast_layers = $passes/" -e "s/^plate_diameters = .*$/plate_diameters = $plate/" \
  -e "s/^timeout_s = .*$/timeout_s = 400000/" sweeps/layers-gaboriault.toml > "$toml"
grep -q "^timeout_s = 400000$" "$toml"
grep -q "^least_layers = $passes$" "$toml"
[ "$freeze" != 0 ] && sed -i "s/^least_layers = $passes$/least_layers = $passes\nfreeze_depth_diameters = $freeze/" "$toml"
if [ -n "${KEY:-}" ]; then
  sed -i "s/^least_layers = $passes$/least_layers = $passes\n$KEY/" "$toml"
  grep -qx "$KEY" "$toml"
fi
while read -r label mu mur gamma; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  name=$label-plate$plate
  [ "$freeze" != 0 ] && name=$name-freeze$freeze
  [ "$passes" != 21 ] && name=$name-passes$passes
  [ -n "${TAG:-}" ] && name=$name-$TAG
  [ -s "$out/twenty-$name.json" ] && { echo "$name: recorded"; continue; }
  ours=$(python3 -c "print(f'{4/3*$gamma:.4g}')")
  dir=runs/twenty/$name
  ( while sleep 30; do mkdir -p "$out/twenty/$name"; cp "$dir"/pass.*.json "$out/twenty/$name/" 2>/dev/null || true; done ) &
  copier=$!
  "${SWEEP:-target/release/sweep}" run "$toml" --json --out "$dir" \
    --set "blade_speed=0.1,friction=$mu,rolling_friction=$mur,surface_energy=$ours" \
    > "$out/twenty-$name.json.part" 2> "$out/twenty-$name.err" || true
  kill $copier 2>/dev/null || true
  mkdir -p "$out/twenty/$name"; cp "$dir"/pass.*.json "$out/twenty/$name/" 2>/dev/null || true
  if grep -q '"layers"' "$out/twenty-$name.json.part"; then
    mv "$out/twenty-$name.json.part" "$out/twenty-$name.json"
  else
    rm -f "$out/twenty-$name.json.part"   # interrupted: run again to go on from its last pass
  fi
done <<< "$cases"
rm -f "$toml"
