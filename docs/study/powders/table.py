#!/usr/bin/env python3
"""The real-powder study's table: one row per point in points/*.json (docs/study/powders.md)."""
import glob, json, os, sys

here = os.path.dirname(os.path.abspath(__file__))
rows = []
for path in sorted(glob.glob(os.path.join(here, "points", "*.json"))):
    name = os.path.basename(path)[:-5]
    try:
        r = json.load(open(path))
    except json.JSONDecodeError:
        continue
    m = r if "mfr" in r else r.get("measured") or {}
    fail = "" if "mfr" in r else r.get("class", "failed")
    p = m.get("parameters", {})
    st = m.get("steady_state") or {}
    rows.append((name, p, m, st, fail))
print("| point | mean D mm | gap mm | v m/s | γ J/m² | layer packing ± SE | MFR ± SE | particles | steps | CPU s | stop |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name, p, m, st, fail in rows:
    print("| {} | {} | {} | {} | {:g} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {} | {} | {:.0f} | {} |".format(
        name, round((m.get("sizes") or {}).get("mean_diameter", p.get("diameter", 0) * 1e-3) * 1e3, 4), p.get("gap"), p.get("blade_speed"), p.get("surface_energy", 0),
        m.get("layer_packing", float("nan")), m.get("layer_packing_se", float("nan")),
        m.get("mfr", float("nan")), m.get("mfr_se") or float("nan"), m.get("particles"),
        m.get("steps"), m.get("cpu_time") or 0, fail or st.get("stop", "")))
