#!/bin/bash
# Issue 10's measurements (BENCHMARKS.md "Fidelity"): run time against error over 8 points × 2
# pile seeds of the thesis 4-D space, the presets and candidate fast variants side by side; then
# the mean CPU per point over a 24-point LDS draw, before (the previous defaults) and after (the
# fast preset), in one run. Resumable: finished runs are read back from OUT/runs.
#
#   bash scripts/fidelity_bench.sh [OUT]        # ~35 min on two free cores
set -euo pipefail
OUT=${1:-runs/fidelity-study}
SWEEP=${SWEEP:-target/release/sweep}
FILE=sweeps/thesis-lds.toml
# The defaults before issue 10: 0.2 × Rayleigh, full stiffness, 6 mesh cells across, two falls
# before the first rest check at 0.01 √(gD), skin 0.25 D.
BEFORE="before:rayleigh_fraction=0.2,stiffness_factor=1,mesh_cells_across=6,settle_min_falls=2,rest_speed=0.01,skin_diameters=0.25"
# The fast preset without the stiffness reduction, and with a looser rest, a larger skin.
STIFF="stiff:stiffness_factor=1"
REST="rest05:rest_speed=0.05"
SKIN="skin1:skin_diameters=1.0"
"$SWEEP" bench fidelity "$FILE" --points 8 --seeds 2 --jobs 2 --out "$OUT/bench8" \
    --variant "$BEFORE" --variant "$STIFF" --variant "$REST" --variant "$SKIN"
"$SWEEP" bench fidelity "$FILE" --points 24 --seeds 1 --jobs 2 --presets fast --out "$OUT/lds24" \
    --variant "$BEFORE"
