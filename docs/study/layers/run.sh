#!/usr/bin/env bash
# The layers study (docs/study/layers.md): Gaboriault et al. 2025's measured multi-layer case,
# PS1–PS3, one point each on the layers layout, then PS1's powder as one layer on the default
# scene at 100 and 200 µm (single-100, single-200). Resumable: a case whose record exists is
# skipped. Run from the repository's root with
# target/release/sweep built (or SWEEP=path); one LIGGGHTS process at a time.
#   bash docs/study/layers/run.sh            # every case not yet recorded
#   bash docs/study/layers/run.sh PS1        # one (or single-100, single-200)
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=docs/study/layers/record
mkdir -p "$out"
base=sweeps/layers-gaboriault.toml
# label sliding rolling surface-energy (theirs, DMT, J/m²; ours is 4/3 of it: the same pull-off)
cases="PS1 0.20 0.10 3.5e-4
PS2 0.20 0.20 2.5e-4
PS3 0.40 0.36 8.0e-5"
want=${1:-}
while read -r label mu mur gamma; do
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  ours=$(python3 -c "print(f'{4/3*$gamma:.4g}')")
  echo "$label: friction $mu, rolling $mur, surface energy $ours J/m2 ($gamma DMT)" >&2
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run "$base" --json \
    --set "blade_speed=0.1,friction=$mu,rolling_friction=$mur,surface_energy=$ours" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done <<< "$cases"

# The same powder (PS1) as one layer at a gap on the default scene: the answer every other layout
# gives, at the case's layer (100 µm) and its first layer's gap (200 µm).
for gap in 100 200; do
  label=single-$gap
  [ -n "$want" ] && [ "$want" != "$label" ] && continue
  [ -s "$out/$label.json" ] && { echo "$label: recorded"; continue; }
  start=$(date +%s)
  "${SWEEP:-target/release/sweep}" run docs/study/layers/gaboriault-single.toml --json \
    --set "blade_speed=0.1,gap=$(python3 -c "print($gap/1000)")" \
    > "$out/$label.json.part" 2> "$out/$label.err" || true
  mv "$out/$label.json.part" "$out/$label.json"
  echo "$label: $(( $(date +%s) - start )) s wall" >&2
done
