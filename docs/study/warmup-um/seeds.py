# Whether the SE the 35 µm point reports covers the scatter between seeds
# (docs/study/warmup-um.md "The numerical choices at 35 µm"): the records default (seed 1) and
# seed2…seed10 of numerics.sh; the SD between seeds against the mean reported SE, and each
# seed's z from the mean of the others.
#   python3 docs/study/warmup-um/seeds.py
import json, math, os
here = os.path.join(os.path.dirname(__file__), "numerics")
names = ["default"] + [f"seed{k}" for k in range(2, 11)]
runs = [(n, json.load(open(os.path.join(here, n + ".json"))))
        for n in names if os.path.exists(os.path.join(here, n + ".json"))]
m = [r["mfr"] for _, r in runs]
se = [r["mfr_se"] for _, r in runs]
n = len(m)
mean = sum(m) / n
sd = math.sqrt(sum((v - mean) ** 2 for v in m) / (n - 1))
print(f"{n} seeds: MFR {mean:.4f}, SD between seeds {sd:.4f}, mean reported SE {sum(se)/n:.4f}, ratio {sd/(sum(se)/n):.2f}")
zs = []
for i, (name, r) in enumerate(runs):
    others = m[:i] + m[i + 1:]
    mo = sum(others) / len(others)
    z = (m[i] - mo) / math.sqrt(se[i] ** 2 + sd ** 2 / len(others))
    zs.append(z)
    print(f"  {name:8s} {m[i]:.4f} ± {se[i]:.4f}  z {z:+.2f}  CPU {r['cpu_time']:.0f} s")
print(f"RMS z {math.sqrt(sum(z * z for z in zs) / n):.2f}")
