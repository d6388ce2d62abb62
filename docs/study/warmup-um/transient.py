#!/usr/bin/env python3
"""Where the conveyor's start-up transient ends, and the bias a warm-up of w leaves, at any scale.

    python3 docs/study/warmup-um/transient.py RUNS_DIR [RUNS_DIR ...] [--window 8]

Reads every case (a directory with result.json) of long runs with no warm-up and no precision
stop (docs/study/warmup-um/transient.sh; the millimetre study's docs/study/recoater/transient-long
reads the same way). For each case:

- t_g = √(H/g), H = gap + heap_height: the held heap's gravity time; a heap length
  (H / tan 30°) and a heap turnover (the heap's mass over the steady mass flow through the gap);
- MSER's cut (White 1997) of the whole block series, in time, in t_g, in travel (D and heap
  lengths) and in turnovers; MFR after the cut with its SE (the blocks' SD over √n, widened by
  √((1+r)/(1−r)) for their lag-1 autocorrelation r ≥ 0);
- the bias of a point measured after a warm-up w, as transient_bias.py defines it: the mean of
  the WINDOW blocks after the warm-up over the mean of the run's last half, minus one. The
  warm-up's blocks are counted as the deck counts them (ceil(max(w·v, 10 D) / block)). Its error
  bar is the window mean's SE and the tail's combined. Tabulated against w in t_g and in s.
"""
import glob, json, math, os, statistics, sys

G = 9.81
T_G = [0, 1, 2, 3, 4, 5, 6, 6.5, 8, 10]
RULE = 6.5  # the default warm-up, √(H/g) (src/scene/settings.rs WARMUP_HEAP_FALLS)
SECONDS = [0.005, 0.01, 0.02, 0.03, 0.05, 0.1, 0.15, 0.2, 0.3]


def mser(y):
    n = len(y)
    best, best_v = 0, float("inf")
    for d in range(0, n // 2 + 1):
        w = y[d:]
        if len(w) < 2:
            break
        v = statistics.pvariance(w) / len(w)
        if v < best_v:
            best, best_v = d, v
    return best


def se(y):
    """SE of the mean of y, widened for lag-1 autocorrelation."""
    n = len(y)
    if n < 3:
        return float("nan")
    m = statistics.fmean(y)
    var = statistics.pvariance(y)
    r = 0.0
    if var > 0:
        r = sum((y[i] - m) * (y[i + 1] - m) for i in range(n - 1)) / (n * var)
    r = min(max(r, 0.0), 0.8)
    return statistics.stdev(y) / math.sqrt(n) * math.sqrt((1 + r) / (1 - r))


def from_log(case):
    """A run stopped by hand (`truncated`: {"cpu_time": s, "why": ...}): its blocks from the
    deck's log, as src/measure/steady.rs reads them, and its point from the case's sweep file."""
    import re, tomllib
    log = open(os.path.join(case, "log.partial" if os.path.exists(os.path.join(case, "log.partial")) else "log.liggghts")).read()
    deck = open(os.path.join(case, "in.liggghts")).read()
    dt = float(re.search(r"^timestep\s+(\S+)", deck, re.M).group(1))
    block_steps = int(re.search(r"# Blocks of (\d+) steps", deck).group(1))
    gone = re.search(r"^region gone block (\S+) (\S+) (\S+) (\S+)", deck, re.M)
    depth = float(gone.group(4)) - float(gone.group(3))
    sweep = tomllib.load(open(case + ".toml", "rb"))
    p = {k: (v["value"] if isinstance(v, dict) and "value" in v else v) for k, v in sweep["parameters"].items()}
    rho, gap, v = p["density"], p["gap"] * 1e-3, p["blade_speed"]
    ideal = rho * depth * gap * v * dt * block_steps
    y, before, heap_mass = [], 0.0, []
    for m in re.finditer(r"^demsweep: block \d+ step \d+ gone (\S+) strip (\S+) heap \d+ heapmass (\S+)", log, re.M):
        g, s_, hm = map(float, m.groups())
        y.append((g + s_ - before) / ideal)
        before = s_
        heap_mass.append(hm / depth)
    t = json.load(open(os.path.join(case, "truncated")))
    d_mm = p.get("diameter")
    if d_mm is None:  # a size distribution: the block is 5 of its number-mean diameters
        d_mm = v * dt * block_steps / 5.0 * 1e3
    h = len(heap_mass) // 2
    return {
        "parameters": {**p, "diameter": d_mm},
        "steady_state": {"block_mfr": y, "block_diameters": v * dt * block_steps / (d_mm * 1e-3),
                         "heap_mass_per_width": statistics.fmean(heap_mass[h:]) if heap_mass else float("nan")},
        "mfr": statistics.fmean(y[len(y) // 2:]), "cpu_time": t.get("cpu_time"),
        "steps": len(y) * block_steps, "particles": None, "truncated": True,
    }


def fmt(x):
    return "–" if x is None else f"{x:g}"


def load(dirs):
    for runs in dirs:
        for case in sorted(glob.glob(os.path.join(runs, "*"))):
            f = os.path.join(case, "result.json")
            if not os.path.isdir(case):
                continue
            if os.path.exists(f):
                r = json.load(open(f))
            elif os.path.exists(os.path.join(case, "truncated")):
                r = from_log(case)
            else:
                continue
            st, p = r["steady_state"], r["parameters"]
            v, gap, heap = p["blade_speed"], p["gap"], p.get("heap_height", 20.0)
            # The scene's diameter: a size distribution's number mean, not the `diameter`
            # parameter it leaves unused, from the deck's block (5 D of travel) where it is kept.
            d_mm = p.get("diameter")
            deck = os.path.join(case, "in.liggghts")
            if os.path.exists(deck):
                import re
                text = open(deck).read()
                dt = float(re.search(r"^timestep\s+(\S+)", text, re.M).group(1))
                steps = int(re.search(r"# Blocks of (\d+) steps", text).group(1))
                d_mm = v * dt * steps * 1e3 / st["block_diameters"]
            h_m = (gap + heap) * 1e-3
            block_mm = st["block_diameters"] * d_mm
            yield dict(
                name=os.path.basename(case) + (" (stopped by hand)" if r.get("truncated") else ""), d=d_mm, v=v, gap=gap, heap=heap,
                gamma=p.get("surface_energy", 0.0), y=st["block_mfr"], block_mm=block_mm,
                block_s=block_mm * 1e-3 / v, tg=math.sqrt(h_m / G),
                heap_len=(gap + heap) / math.tan(math.radians(30)),
                heap_mass=st.get("heap_mass_per_width") or float("nan"),
                rho=p.get("density", 7980.0), cpu=r.get("cpu_time") or float("nan"),
                steps=r.get("steps") or 0, mfr=r["mfr"], particles=r.get("particles"),
            )


def warmup_blocks(c, w_s):
    travel_d = max(w_s * c["v"] * 1e3, 10 * c["d"]) / c["d"]
    return math.ceil(travel_d / (c["block_mm"] / c["d"]) - 1e-9)


def bias_at(c, w_s, window):
    y = c["y"]
    k = warmup_blocks(c, w_s)
    half = len(y) // 2
    if k + window > len(y) - half // 2:  # the window must end inside the run, before its last quarter
        return None
    tail = y[half:]
    t, win = statistics.fmean(tail), y[k:k + window]
    if t <= 0:
        return None
    b = statistics.fmean(win) / t - 1
    # The window's SE from the tail's block scatter (a short window's own SD is too noisy).
    s_w = se(tail) * math.sqrt(len(tail) / window)
    s = (1 + b) * math.hypot(s_w / statistics.fmean(win) if statistics.fmean(win) > 0 else 0, se(tail) / t)
    return b, s


def settled_from(c, window):
    """The least warm-up, in t_g (a 0.25 t_g grid), from which the bias at every later warm-up
    up to 10 t_g that the run can judge is within 2 SE of zero; None if the run is too short."""
    grid = [0.25 * i for i in range(0, 41)]  # to 10 t_g: further on, slow drifts of the tail, not the start
    judged = [(x, bias_at(c, x * c["tg"], window)) for x in grid]
    judged = [(x, b) for x, b in judged if b is not None]
    if not judged:
        return None
    last_bad = None
    for x, (b, s) in judged:
        if abs(b) > 2 * s:
            last_bad = x
    if last_bad is None:
        return 0.0
    later = [x for x, _ in judged if x > last_bad]
    return later[0] if later else None


def main():
    args = sys.argv[1:]
    window = 8
    if "--window" in args:
        i = args.index("--window")
        window = int(args[i + 1])
        del args[i:i + 2]
    cases = list(load(args))
    print("Where MSER cuts the transient (whole block series):\n")
    print("| case | D µm | v m/s | gap mm | heap mm | γ J/m² | t_g ms | Fr_H | blocks (block ms) | cut blocks | time s | t_g | travel D | heap lengths | turnovers | MFR ± SE after the cut | bias within 2 SE from (t_g) | particles | steps | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for c in cases:
        y = c["y"]
        cut = mser(y)
        w = y[cut:]
        m, s = statistics.fmean(w), se(w)
        t = cut * c["block_s"]
        travel = cut * c["block_mm"]
        # A turnover: the heap's mass per width over the steady flow per width, ρ·gap·v·MFR.
        flow = c["rho"] * c["gap"] * 1e-3 * c["v"] * m
        turn = c["heap_mass"] / flow if flow > 0 else float("nan")
        fr = c["v"] / math.sqrt(G * (c["gap"] + c["heap"]) * 1e-3)
        print(f"| {c['name']} | {c['d']*1e3:.1f} | {c['v']} | {c['gap']:g} | {c['heap']:g} | {c['gamma']:g} | {c['tg']*1e3:.1f} | {fr:.2f} | "
              f"{len(y)} ({c['block_s']*1e3:.2f}) | {cut} | {t:.3f} | {t / c['tg']:.1f} | {travel / c['d']:.0f} | {travel / c['heap_len']:.2f} | "
              f"{t / turn:.2f} | {m:.4f} ± {s:.4f} | {fmt(settled_from(c, window))} | {c['particles'] or '–'} | {c['steps']} | {c['cpu']:.0f} |")
    for unit, grid, to_s in (("t_g = √(H/g)", T_G, lambda c, x: x * c["tg"]), ("s", SECONDS, lambda c, x: x)):
        print(f"\nBias of MFR (%) after a warm-up in {unit}, the next {window} blocks against the run's last half (± its SE):\n")
        print("| case | " + " | ".join(f"{x:g}" for x in grid) + " |")
        print("|---|" + "---|" * len(grid))
        for c in cases:
            row = []
            for x in grid:
                b = bias_at(c, to_s(c, x), window)
                row.append("–" if b is None else f"{100*b[0]:+.0f} ± {100*b[1]:.0f}")
            print(f"| {c['name']} | " + " | ".join(row) + " |")
        # Over the cases: the mean bias, its SE, and the RMS of bias/SE (1 where only noise is left).
        mean_row, z_row = [], []
        for x in grid:
            b = [bias_at(c, to_s(c, x), window) for c in cases]
            b = [e for e in b if e is not None]
            if len(b) < 2:
                mean_row.append("–"); z_row.append("–")
                continue
            m = statistics.fmean(e[0] for e in b)
            sm = math.sqrt(sum(e[1] ** 2 for e in b)) / len(b)
            mean_row.append(f"{100*m:+.1f} ± {100*sm:.1f} ({len(b)})")
            z_row.append(f"{math.sqrt(statistics.fmean((e[0] / e[1]) ** 2 for e in b)):.1f}")
        print("| mean (cases) | " + " | ".join(mean_row) + " |")
        print("| RMS bias/SE | " + " | ".join(z_row) + " |")


if __name__ == "__main__":
    main()
