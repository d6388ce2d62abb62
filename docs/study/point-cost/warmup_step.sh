#!/usr/bin/env bash
# The warm-up at a longer timestep (BENCHMARKS.md "Where a point's CPU goes"): the first 100
# points of sweeps/thesis-lds.toml from rest, as they are (base) and with the warm-up's blocks
# run at 1.5 times the step (0.5 Rayleigh times, the measured safe bound; the window at the
# usual 0.33), one run at a time each, side by side. Then:
#   python3 docs/study/warm-start/compare.py WORK/base WORK/warmdt
#   python3 docs/study/point-cost/settled_se.py pairs WORK/base WORK/warmdt
#   bash docs/study/point-cost/warmup_step.sh [WORK]      (resumable: `sweep lds` keeps what ran)
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${SWEEP_BIN:-$PWD/target/release/sweep}
work=${1:-/tmp/warmup-step}
mkdir -p "$work"
python3 - templates/conveyor.liggghts.tera > "$work/warmdt.tera" <<'PY'
import sys
lines = open(sys.argv[1]).read().split("\n")
assert "label blockloop" in lines and "run {{ scene.conveyor.block_steps }}" in lines, "the conveyor deck changed"
out = []
for l in lines:
    if l == "label blockloop":
        out += ["{%- set wsteps = (scene.conveyor.block_steps / 1.5) | round | int %}",
                "timestep        {{ scene.timestep * 1.5 }}", "variable nsteps equal {{ wsteps }}"]
    if l == "run {{ scene.conveyor.block_steps }}":
        out += ["run ${nsteps}",
                'if "${block} == {{ scene.conveyor.warmup_blocks }}" then "timestep {{ scene.timestep }}" '
                '"variable nsteps equal {{ scene.conveyor.block_steps }}"']
        continue
    out.append(l)
print("\n".join(out))
PY
cp sweeps/thesis-lds.toml "$work/base.toml"
sed "s|^\[scene\]$|[scene]\ntemplate = \"$work/warmdt.tera\"|" sweeps/thesis-lds.toml > "$work/warmdt.toml"
for v in base warmdt; do
  "$bin" lds "$work/$v.toml" --step 100 --max 100 --hold 1000 --jobs 1 --out "$work/$v" > "$work/$v.log" 2>&1 &
done
wait
