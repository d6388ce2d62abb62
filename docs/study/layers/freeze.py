#!/usr/bin/env python3
"""The deep loose bed held still against the whole bed moving: per pass, its CPU and relative
density, from the runs' logs and pass records (run directories of twenty.sh), and the layer
groups of Gaboriault et al. 2025 in step (their layer n is our pass n + 1).

    python3 docs/study/layers/freeze.py runs/twenty/PS1-plate24 runs/twenty/PS1-plate24-freeze10 \
        > docs/study/layers/record/freeze.txt
"""
import json
import math
import re
import sys
from pathlib import Path


def deck_numbers(run):
    deck = (run / "in.pass.1").read_text() if (run / "in.pass.1").exists() else (run / "in.liggghts").read_text()
    x0, x1 = map(float, re.search(r"region plate block (\S+) (\S+)", deck).groups())
    depth = float(re.search(r"region domain block 0 \S+ 0 (\S+)", deck).group(1))
    rho = float(re.search(r"density constant (\S+)", deck).group(1))
    tops = [float(t) for t in re.findall(r"fix top\d+ all mesh/surface file feed.stl type 2 move 0 0 (\S+)", deck)]
    return (x1 - x0) * depth, rho, tops


def passes(run):
    area, rho, _ = deck_numbers(run)
    out, before, buried = [], 0.0, 0.0
    k = 1
    while (run / f"pass.{k}.json").exists():
        log = (run / f"log.pass.{k}").read_text(errors="replace") if (run / f"log.pass.{k}").exists() else ""
        m = re.search(rf"demsweep: layer {k} step \S+ plate (\S+) count (\S+)", log)
        if not m:
            break
        # A shed bed (bury) removed its deep part after earlier passes' layers were counted: it
        # is still on the plate.
        mass = float(m.group(1)) + buried
        b = re.search(rf"demsweep: buried {k} mass (\S+)", log)
        buried += float(b.group(1)) if b else 0.0
        cpu = json.loads((run / f"pass.{k}.json").read_text())["cpu_time"]
        out.append((k, cpu, (mass - before) / (rho * area)))
        before = mass
        k += 1
    return out


def mean_se(v):
    n = len(v)
    if n < 2:
        return (v[0] if v else math.nan), math.nan
    m = sum(v) / n
    return m, math.sqrt(sum((x - m) ** 2 for x in v) / (n - 1) / n)


def main(dirs):
    layer, clearance = 1e-4, 1e-4  # sweeps/layers-gaboriault.toml: 100 µm layers, 100 µm clearance
    runs = [(Path(d).name, passes(Path(d))) for d in dirs]
    drop = lambda k: layer + clearance if k == 1 else layer
    print("pass | " + " | ".join(f"{n}: CPU s, rel. density" for n, _ in runs))
    for k in range(1, max(len(p) for _, p in runs) + 1):
        cells = []
        for _, p in runs:
            row = next((r for r in p if r[0] == k), None)
            cells.append(f"{row[1]:.0f}, {row[2] / drop(k):.3f}" if row else "—")
        print(f"{k} | " + " | ".join(cells))
    print()
    for n, p in runs:
        rel = {k: dep / drop(k) for k, _, dep in p}
        cpu = {k: c for k, c, _ in p}
        groups = [("their layers 2–10 (our passes 3–11)", range(3, 12)), ("their layers 11–20 (our passes 12–21)", range(12, 22))]
        parts = []
        for name, ks in groups:
            v = [rel[k] for k in ks if k in rel]
            if v:
                m, se = mean_se(v)
                parts.append(f"{name}: {m:.3f} ± {se:.3f} ({len(v)} passes)")
        ratio = f"; pass {max(cpu)} / pass 5 CPU = {cpu[max(cpu)] / cpu[5]:.2f}" if 5 in cpu else ""
        print(f"{n}: {len(p)} passes, {sum(cpu.values()):.0f} CPU s; " + "; ".join(parts) + ratio)


if __name__ == "__main__":
    main(sys.argv[1:])
