#!/usr/bin/env bash
# Warm starts against cold starts, on the same points, one run at a time (BENCHMARKS.md "Warm
# start"): the first 24 points of the thesis space's LDS draw (sweeps/thesis-lds.toml) and of the
# machine-speed space (docs/study/thesis/machine-speeds.toml), every point run (no screen).
#
#   bash docs/study/warm-start/warm.sh [VARIANT ...]   (default: every variant of both spaces)
#
# A variant is a space (thesis or slow) and a way of computing it (SPACE-cold, -warm, -new, -long,
# -thesis, below), or NAME=SPACE:key=value,... for other [scene] knobs (e.g.
# thesis-w06=thesis:warm_warmup_s=0.06). Each runs `sweep lds --step N --max N --jobs 1` (N =
# POINTS, default 24) in WORK/<variant> (default WORK=/tmp/warm-study), which continues a
# directory it finds; then compare.py prints the tables. Needs target/release/sweep
# (scripts/setup.sh).
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${SWEEP_BIN:-$PWD/target/release/sweep}
work=${WORK:-/tmp/warm-study}
points=${POINTS:-24}
mkdir -p "$work"

space_file() {
  case $1 in
    thesis) echo sweeps/thesis-lds.toml ;;
    slow) echo docs/study/thesis/machine-speeds.toml ;;
    *) echo "warm.sh: unknown space '$1' (thesis or slow)" >&2; exit 2 ;;
  esac
}

run_variant() { # name, space, [scene] lines
  local name=$1 space=$2 scene=$3 file="$work/$1.toml"
  # The space's file with its [scene] table extended, and every point run.
  { sed "s/^\[scene\]$/[scene]\n$scene/" "$(space_file "$space")"; printf '\n[run]\nscreen = false\n'; } > "$file"
  echo "warm.sh: $name" >&2
  "$bin" lds "$file" --step "$points" --max "$points" --hold 1000 --jobs 1 --out "$work/$name" > "$work/$name.log" 2>&1 || true
}

variants=("$@")
[ ${#variants[@]} -gt 0 ] || variants=(thesis-cold thesis-warm thesis-new thesis-long thesis-thesis slow-cold slow-warm slow-new)
for v in "${variants[@]}"; do
  case $v in
    # Cold: from rest, to the scene's fixed 5 % target. Warm: the same, warm-started. New: the
    # defaults (warm-started, to the precision the sweep chooses). Long: cold to a 1.5 % target
    # (the truth the others are judged against). Thesis: the `thesis` fidelity preset.
    *-cold) run_variant "$v" "${v%-cold}" 'warm_start = false\nprecision = "fixed"' ;;
    *-warm) run_variant "$v" "${v%-warm}" 'warm_start = true\nprecision = "fixed"' ;;
    *-new) run_variant "$v" "${v%-new}" '' ;;
    *-long) run_variant "$v" "${v%-long}" 'warm_start = false\nmfr_rel_se = 0.015\nmfr_abs_se = 0.0015\nwindow_cap_diameters = 3000' ;;
    *-thesis) run_variant "$v" "${v%-thesis}" 'fidelity = "thesis"' ;;
    *=*:*)
      name=${v%%=*}; rest=${v#*=}; space=${rest%%:*}; knobs=${rest#*:}
      run_variant "$name" "$space" "$(echo "$knobs" | sed 's/,/\\n/g')" ;;
    *) echo "warm.sh: unknown variant '$v'" >&2; exit 2 ;;
  esac
done

# DENSE=N: the first N points of the thesis space's draw on the defaults (thesis-dense), then the
# last 24 of them run cold to a 1.5 % target (thesis-dense-long/*.json, one `sweep run` each):
# warm starts where a sweep has neighbours near (N = 200: a median distance of about 0.25).
if [ -n "${DENSE:-}" ]; then
  run_dense() {
    local file="$work/thesis-dense.toml" long="$work/thesis-dense-long"
    { cat sweeps/thesis-lds.toml; printf '\n[run]\nscreen = false\n'; } > "$file"
    "$bin" lds "$file" --step "$DENSE" --max "$DENSE" --hold 1000 --jobs 1 --out "$work/thesis-dense" > "$work/thesis-dense.log" 2>&1 || true
    sed "s/^\[scene\]$/[scene]\nwarm_start = false\nmfr_rel_se = 0.015\nmfr_abs_se = 0.0015\nwindow_cap_diameters = 3000/" "$file" > "$long.toml"
    mkdir -p "$long"
    python3 - "$work/thesis-dense/results.csv" "$DENSE" <<'PY' | while read -r index set; do
import csv, sys
rows = [r for r in csv.DictReader(open(sys.argv[1])) if int(r["index"]) >= int(sys.argv[2]) - 24]
for r in rows:
    print(r["index"], ",".join(f"{k}={r[k]}" for k in ("friction", "diameter", "gap", "blade_speed")))
PY
      [ -s "$long/$index.json" ] || "$bin" run "$long.toml" --set "$set" --json > "$long/$index.json.tmp" 2>/dev/null && mv "$long/$index.json.tmp" "$long/$index.json" || true
    done
  }
  run_dense
fi
