#!/usr/bin/env bash
# PS2 and PS3 at seeds 2 and 3 on the study's bed (the 24 D plate, held 4 D under the top), all
# 21 passes: with seed 1 (twenty-PS2/PS3-plate24-freeze4-bury.json) three seeds of each set, as
# PS1 has, so that the sets' plateaus are told apart by pooled means (issue: the experiment in
# step). Each run goes on from its last pass when run again; finished ones are skipped.
#   nice -n 10 bash docs/study/layers/seeds.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
for seed in 2 3; do
  for set in PS2 PS3; do
    FREEZE=4 KEY="seed = $seed" TAG="bury-seed$seed" bash docs/study/layers/twenty.sh "$set"
  done
done
