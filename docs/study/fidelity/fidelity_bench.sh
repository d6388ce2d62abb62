#!/bin/bash
# The measurements of BENCHMARKS.md "Fidelity": run time against error over 8 points × 2
# pile seeds of the thesis 4-D space, the presets and candidate fast variants side by side; then
# the mean CPU per point over a 24-point LDS draw, before (the previous defaults) and after (the
# fast preset), in one run. Resumable: finished runs are read back from OUT/runs.
#
#   bash docs/study/fidelity/fidelity_bench.sh [OUT]        # ~35 min on two free cores
set -euo pipefail
OUT=${1:-runs/fidelity-study}
SWEEP=${SWEEP:-target/release/sweep}
FILE=sweeps/thesis-lds.toml
# The defaults before the fast preset: 0.2 × Rayleigh, full stiffness, 6 mesh cells across, two falls
# before the first rest check at 0.01 √(gD), skin 0.25 D.
BEFORE="before:rayleigh_fraction=0.2,stiffness_factor=1,mesh_cells_across=6,settle_min_falls=2,rest_speed=0.01,skin_diameters=0.25"
# The fast preset with a looser settle, a finer mesh, a softer contact.
"$SWEEP" bench fidelity "$FILE" --points 8 --seeds 2 --jobs 2 --out "$OUT/bench8" \
    --variant "$BEFORE" \
    --variant stiff:rest_speed=0.02,settle_min_falls=1 \
    --variant stiff6:rest_speed=0.02,settle_min_falls=1,mesh_cells_across=6 \
    --variant soft6r:mesh_cells_across=6,stiffness_factor=0.25 \
    --variant soft:rest_speed=0.02,settle_min_falls=1,stiffness_factor=0.25
"$SWEEP" bench fidelity "$FILE" --points 24 --seeds 1 --jobs 2 --presets fast --out "$OUT/lds24" \
    --variant "$BEFORE"
