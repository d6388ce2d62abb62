#!/usr/bin/env python3
"""The real-powder study's tables (docs/study/powders.md): one row per point in points/*.json, or
with `shaheen`, the layer packing over Shaheen et al.'s friction grid by blade speed."""
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
if sys.argv[1:] == ["shaheen"]:
    print("| sliding μ | rolling μ_r | 100 mm/s | 50 mm/s | 10 mm/s |")
    print("|---|---|---|---|---|")
    for mu, mur in [("0.05", "0.005"), ("0.05", "0.4"), ("0.5", "0.005"), ("0.5", "0.4"), ("0.275", "0.2")]:
        cells = []
        for v in ["0.1", "0.05", "0.01"]:
            found = [r for r in rows if r[0] == f"shaheen-v{v}-mu{mu}-mur{mur}"]
            if not found:
                cells.append("not run yet")
                continue
            _, _, m, _, fail = found[0]
            cell = "{:.3f} ± {:.3f}".format(m.get("layer_packing", float("nan")), m.get("layer_packing_se", float("nan")))
            cells.append(cell + (f" ({fail})" if fail else ""))
        print(f"| {mu} | {mur} | " + " | ".join(cells) + " |")
    sys.exit(0)
print("| point | mean D mm | gap mm | v m/s | γ J/m² | layer packing ± SE | MFR ± SE | particles | steps | CPU s | stop |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name, p, m, st, fail in rows:
    print("| {} | {} | {} | {} | {:g} | {:.3f} ± {:.3f} | {:.3f} ± {:.3f} | {} | {} | {:.0f} | {} |".format(
        name, round((m.get("sizes") or {}).get("mean_diameter", p.get("diameter", 0) * 1e-3) * 1e3, 4), p.get("gap"), p.get("blade_speed"), p.get("surface_energy", 0),
        m.get("layer_packing", float("nan")), m.get("layer_packing_se", float("nan")),
        m.get("mfr", float("nan")), m.get("mfr_se") or float("nan"), m.get("particles"),
        m.get("steps"), m.get("cpu_time") or 0, fail or st.get("stop", "")))
