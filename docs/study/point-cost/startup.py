#!/usr/bin/env python3
"""The start-up study's deck variants and its table (docs/study/point-cost/startup.sh).

    python3 startup.py variants TEMPLATE WORK   # writes WORK/{base,settle,ramp}.tera
    python3 startup.py table WORK               # mean block MFR over the seeds, by 4 blocks
"""
import glob, json, os, statistics, sys

MOVE = "fix substrate substrate move linear"
# A block: 5 D = 10 mm at 1.4 m/s.
BLOCK_S = 0.010 / 1.4
WARMUPS_S = (0.05, 0.1, 0.15, 0.2, 0.3)
START = 'print "demsweep: settled at step 0"'
ON_SUBSTRATE = "{%- if scene.substrate_particles > 0 %}"


def variants(template, work):
    lines = open(template).read().split("\n")
    assert any(l.startswith(MOVE) for l in lines) and START in lines, "the conveyor deck changed"
    for name in ("base", "settle", "ramp"):
        out = []
        for l in lines:
            if name != "base" and l.startswith(MOVE):
                continue  # the substrate starts below, once the heap is in place
            if name != "base" and l == START:
                if name == "settle":
                    out += ["run 2500", ON_SUBSTRATE, MOVE + " -{{ scene.blade_speed }} 0 0", "{%- endif %}"]
                else:
                    for k in range(1, 6):
                        out += [ON_SUBSTRATE, f"{MOVE} -{{{{ scene.blade_speed * {k / 6:.4f} }}}} 0 0",
                                "{%- endif %}", "run 300", ON_SUBSTRATE, "unfix substrate", "{%- endif %}"]
                    out += [ON_SUBSTRATE, MOVE + " -{{ scene.blade_speed }} 0 0", "{%- endif %}"]
            out.append(l)
        open(os.path.join(work, name + ".tera"), "w").write("\n".join(out))


def blocks(run):
    for f in ("result.json", "failure.json"):
        p = os.path.join(run, f)
        if os.path.exists(p):
            r = json.load(open(p))
            r = r.get("measured") or r
            return (r.get("steady_state") or {}).get("block_mfr")
    return None


def table(work):
    print("MFR, the mean of the seeds, by 4 blocks (0.029 s) from the start of full speed")
    print("(settle and ramp: the first column also holds what fell through the gap before it)\n")
    for name in ("base", "settle", "ramp"):
        ys = [y for y in (blocks(r) for r in sorted(glob.glob(os.path.join(work, name + "-s*")))
                          if os.path.isdir(r)) if y]
        if not ys:
            continue
        n = min(len(y) for y in ys)
        m = [statistics.fmean(y[i] for y in ys) for i in range(n)]
        cols = " ".join(f"{statistics.fmean(m[i:i + 4]):.3f}" for i in range(0, n, 4))
        # The bias of a point measured after a warm-up w (from the start of full speed): the
        # mean of the next 8 blocks over the last half's (8 seeds: about ±2 % of noise).
        steady = statistics.fmean(m[n // 2:])
        bias = []
        for w_s in WARMUPS_S:
            w = round(w_s / BLOCK_S)
            bias.append(f"{100 * (statistics.fmean(m[w:w + 8]) / steady - 1):+.0f}")
        print(f"{name:7} {len(ys)} seeds  {cols}")
        print(f"{'':7} steady {steady:.3f}; bias after a warm-up of {', '.join(f'{w} s' for w in WARMUPS_S)}: "
              f"{', '.join(b + ' %' for b in bias)}")

if __name__ == "__main__":
    if sys.argv[1:2] == ["variants"] and len(sys.argv) == 4:
        variants(sys.argv[2], sys.argv[3])
    elif sys.argv[1:2] == ["table"] and len(sys.argv) == 3:
        table(sys.argv[2])
    else:
        sys.exit(__doc__)
