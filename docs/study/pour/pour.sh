#!/usr/bin/env bash
# The angle of repose of sweeps/pour.toml (2 mm steel spheres, lifted-cylinder test) at several
# rolling frictions, one pour at a time; one row per pour in docs/study/pour/pour.tsv.
#
#   bash docs/study/pour/pour.sh                 # rolling friction 0.05 0.1 0.2 0.3
#   bash docs/study/pour/pour.sh 0.15 0.25       # others
#
# Run from the repository's root with target/release/sweep built. Each pour is about 90 s of
# CPU (2,000 particles, 3.6 s simulated); its run directory goes to ${POUR_DIR:-/tmp/pour-study}.
set -euo pipefail
SWEEP=${SWEEP:-target/release/sweep}
OUT=${POUR_DIR:-/tmp/pour-study}
TSV=docs/study/pour/pour.tsv
mkdir -p "$OUT"
[ -f "$TSV" ] || printf 'rolling_friction\tangle_deg\tangle_se_deg\tsectors_deg\theight_mm\tfoot_radius_mm\tpacking\trun_out\tcpu_s\tstatus\n' >"$TSV"
for r in "${@:-0.05 0.1 0.2 0.3}"; do
  for rf in $r; do
    dir="$OUT/rf$rf"
    rm -rf "$dir"
    if "$SWEEP" run sweeps/pour.toml --set "rolling_friction=$rf" --out "$dir" >"$dir.out" 2>"$dir.err"; then
      python3 - "$dir/result.json" "$rf" >>"$TSV" <<'PY'
import json, sys
r = json.load(open(sys.argv[1])); h = r["heap"]
print("\t".join([sys.argv[2], f"{h['angle_deg']:.2f}", f"{h['angle_se_deg']:.2f}",
      " ".join(f"{a:.1f}" for a in h["sector_angles_deg"]), f"{h['height_mm']:.1f}",
      f"{h['base_radius_mm']:.1f}", f"{h['packing']:.3f}", str(h["particles_run_out"]),
      f"{r['cpu_time']:.0f}", "done"]))
PY
    else
      reason=$(tail -1 "$dir.err" | tr '\t' ' ')
      printf '%s\t\t\t\t\t\t\t\t\t%s\n' "$rf" "failed: $reason" >>"$TSV"
    fi
  done
done
column -t -s $'\t' "$TSV"
