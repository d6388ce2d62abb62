#!/usr/bin/env python3
# How well a fused bed's passes locate its steady depth (docs/study/layers.md "How well a pass
# locates the steady depth"): for each record, the steady layer's depth and packing ± their SE as
# recorded, the fixed point d* at which the least-squares line of each pass's deposit against the
# depth it met (passes 2 on) keeps the drop, its SE by inverse prediction, the line's slope D',
# and the SEs as the measure now states them (src/scenes/layers/fixed_point.rs: the
# depth's SE at least d*'s, the packing's at least packing × that over d*).
#   python3 docs/study/layers/fixed_point.py docs/study/layers/record/cuts/*machine*.json
import json, math, sys


def fixed_point(passes, t):
    d = [p["effective_thickness_m"] for p in passes]
    g = [p["deposit_m"] for p in passes]
    n = len(d)
    if n < 4:
        return None
    dm, gm = sum(d) / n, sum(g) / n
    sxx = sum((x - dm) ** 2 for x in d)
    sxy = sum((x - dm) * (y - gm) for x, y in zip(d, g))
    if not sxx > 0 or not sxy / sxx > 0:
        return None
    b = sxy / sxx
    rss = sum((y - gm - b * (x - dm)) ** 2 for x, y in zip(d, g))
    s = math.sqrt(rss / (n - 2))
    ds = dm + (t - gm) / b
    return ds, s / b * math.sqrt(1 / n + (ds - dm) ** 2 / sxx), b


print("| record | speed m/s | layer µm | depth µm ± SE (recorded) | d* µm ± SE | D' | depth SE now | packing ± SE (recorded) | packing SE now |")
print("|---|---|---|---|---|---|---|---|---|")
for f in sys.argv[1:]:
    try:
        r = json.load(open(f))
    except (OSError, ValueError):
        continue
    L = r.get("layers")
    if not L or L["bed"] != "fused" or "cpu_time" not in r:
        continue
    t = L["layer_thickness_m"]
    fp = fixed_point(L["passes"][1:], t)
    d, dse = L["effective_thickness_m"], L["effective_thickness_se_m"]
    pk, pse = L["packing"], L["packing_se"]
    v = r["parameters"].get("blade_speed", float("nan"))
    name = f.split("record/")[-1].replace("/result.json", "").replace(".json", "")
    if fp:
        ds, se, b = fp
        print(f"| {name} | {v:.2g} | {t*1e6:.0f} | {d*1e6:.1f} ± {dse*1e6:.1f} | {ds*1e6:.1f} ± {se*1e6:.1f} | {b:.2f} | {max(dse, se)*1e6:.1f} | {pk:.3f} ± {pse:.3f} | {max(pse, pk*se/ds):.3f} |")
    else:
        print(f"| {name} | {v:.2g} | {t*1e6:.0f} | {d*1e6:.1f} ± {dse*1e6:.1f} | — | — | {dse*1e6:.1f} | {pk:.3f} ± {pse:.3f} | {pse:.3f} |")
