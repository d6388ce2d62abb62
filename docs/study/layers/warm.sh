#!/usr/bin/env bash
# Warm start across a sweep (docs/layers.md "Warm start"): the same fused-bed sweep run cold and
# with `warm_start = true`, one point at a time so that each warm point has its finished
# neighbours, and every point's steady layer compared (packing and depth, difference over the
# combined SE), with its passes and CPU. A 2 mm powder on a 12 D plate: cheap enough to run in
# minutes, the same deck and search as the real powders'. Resumable (sweep resume).
#   bash docs/study/layers/warm.sh            # writes record/warm/{cold,warm}.json, warm.txt
set -euo pipefail
cd "$(dirname "$0")/../../.."
sweep=${SWEEP:-target/release/sweep}
out=docs/study/layers/record/warm
mkdir -p "$out" runs/warm
toml=runs/warm/fused.toml
cat > "$toml" <<'T'
name = "warm-study"
[parameters]
blade_speed     = { lo = 0.2, hi = 0.5, unit = "m/s" }
layer_thickness = { lo = 2.0, hi = 4.0, unit = "mm" }
diameter        = 2.0
friction        = 0.3
rolling_friction = 0.1
restitution     = 0.4
[design.lds]
step = 6
max = 6
[scene]
layout = "layers"
bed = "fused"
plate_diameters = 12
layers = 14
T
sed 's/^layers = 14$/layers = 14\nwarm_start = true/' "$toml" > runs/warm/fused-warm.toml
warm=${WARM:-warm}   # the warm sweep's directory and record name (another variant: WARM=warm4)
for mode in cold $warm; do
  file=$toml; [ $mode = $warm ] && file=runs/warm/fused-warm.toml
  dir=runs/warm/$mode
  if [ -f "$dir/manifest.json" ]; then "$sweep" resume "$dir" --jobs 1 -q || true
  else "$sweep" lds "$file" --jobs 1 --out "$dir" -q || true; fi
  python3 - "$dir" > "$out/$mode.json" <<'P'
import json, os, sys
rows = []
for h in sorted(os.listdir(os.path.join(sys.argv[1], "runs"))):
    d = os.path.join(sys.argv[1], "runs", h)
    ok = os.path.exists(os.path.join(d, "result.json"))
    r = json.load(open(os.path.join(d, "result.json" if ok else "failure.json")))
    m = r if ok else r["measured"]
    l = m["layers"]
    rows.append({"steady": ok, "parameters": m["parameters"], "passes": len(l["passes"]),
                 "packing": l["packing"], "packing_se": l["packing_se"],
                 "depth_m": l["effective_thickness_m"], "depth_se_m": l["effective_thickness_se_m"],
                 "cpu_s": m["cpu_time"], "warm_from": (m.get("warm_start") or {}).get("from")})
json.dump(rows, sys.stdout, indent=1)
P
done
python3 - "$out" "$warm" > "$out/../$warm.txt" <<'P'
import json, math, sys
cold = json.load(open(sys.argv[1] + "/cold.json")); warm = json.load(open(sys.argv[1] + f"/{sys.argv[2]}.json"))
key = lambda r: (round(r["parameters"]["blade_speed"], 6), round(r["parameters"]["layer_thickness"], 6))
w = {key(r): r for r in warm}
print(f"{'speed m/s':>9} {'t mm':>5} | {'cold packing':>15} {'warm packing':>15} {'z':>5} | {'cold depth mm':>15} {'warm depth mm':>15} {'z':>5} | passes c/w | CPU s c/w | warm")
tot = [0, 0]
for c in sorted(cold, key=key):
    r = w[key(c)]
    z = lambda a, b, sa, sb: (b - a) / math.hypot(sa, sb)
    zp = z(c["packing"], r["packing"], c["packing_se"], r["packing_se"])
    zd = z(c["depth_m"], r["depth_m"], c["depth_se_m"], r["depth_se_m"])
    tot[0] += c["cpu_s"]; tot[1] += r["cpu_s"]
    flag = lambda r: "" if r["steady"] else " (unsteady)"
    print(f"{key(c)[0]:9.3f} {key(c)[1]:5.2f} | {c['packing']:.3f} ± {c['packing_se']:.3f}{flag(c):>0} {r['packing']:.3f} ± {r['packing_se']:.3f}{flag(r)} {zp:+5.1f} | "
          f"{c['depth_m']*1e3:6.2f} ± {c['depth_se_m']*1e3:5.2f} {r['depth_m']*1e3:6.2f} ± {r['depth_se_m']*1e3:5.2f} {zd:+5.1f} | {c['passes']:>4}/{r['passes']:<4} | {c['cpu_s']:5.1f}/{r['cpu_s']:<5.1f} | {'yes' if r['warm_from'] else 'cold'}")
print(f"total CPU: cold {tot[0]:.0f} s, warm {tot[1]:.0f} s ({tot[1]/tot[0]:.2f})")
P
cat "$out/../$warm.txt"
