#!/usr/bin/env python3
"""How far a fused bed's search has come by each pass: for every finished point of a layers
lattice's records, the depth of powder under the tip of each pass against the point's steady depth
(what a search of 3 passes would hand its first laid pass is pass 4's depth).

    python3 docs/study/layers/search_reach.py docs/study/layers/record/machine-lattice-laid
"""
import glob
import json
import sys

rows = []
for f in glob.glob(sys.argv[1] + "/*/result.json"):
    r = json.load(open(f))
    l, p = r["layers"], r["parameters"]
    depths = [q["effective_thickness_m"] * 1e6 for q in l["passes"]]
    steady, se = l["effective_thickness_m"] * 1e6, l["effective_thickness_se_m"] * 1e6
    rows.append((p["layer_thickness"], p["blade_speed"], steady, se, depths))
print("| layer (µm) | speed (m/s) | steady depth ± SE (µm) | pass 4 against it | passes' depths (µm) |")
print("|---|---|---|---|---|")
for t, v, steady, se, depths in sorted(rows):
    print(f"| {t * 1e3:.0f} | {v:.2f} | {steady:.1f} ± {se:.1f} | {(depths[3] / steady - 1) * 100:+.1f} % | "
          + " ".join(f"{d:.0f}" for d in depths) + " |")
