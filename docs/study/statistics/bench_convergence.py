#!/usr/bin/env python3
"""How many runs LDS and lattice sweeps need to converge, under the thesis rule and the
default, on the stand-in engine over the thesis's 4-D space (BENCHMARKS.md "Convergence: LDS
against lattice").

    python3 docs/study/statistics/bench_convergence.py [--sweep target/release/sweep]

Runs sweeps/thesis-lattice.toml (levels 5, 6, 7, 9, 10) and sweeps/thesis-lds.toml (steps of 400
up to 2,400) with `[run] engine = "stand-in"`, each under `--rule any` (the thesis: any one
statistic within 5 %) and the default (`all`: every statistic within 5 % or 0.01 absolute, for
two consecutive spaces). A reference distribution, 20,000 LDS points all run, says how close
each converged space's statistics are to the space's own.
"""
import argparse
import json
import os
import subprocess
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
STATS = ["mean", "std", "skewness", "kurtosis"]


def standin(name, tmp):
    path = os.path.join(tmp, name)
    with open(os.path.join(ROOT, "sweeps", name)) as f:
        text = f.read()
    with open(path, "w") as f:
        f.write(text + '\n[run]\nengine = "stand-in"\n')
    return path


def run(sweep, args, out):
    t = time.time()
    p = subprocess.run([sweep] + args + ["--out", out, "-q"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f), time.time() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sweep", default=os.path.join(ROOT, "target/release/sweep"))
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="bench-conv-")
    lat, lds = standin("thesis-lattice.toml", tmp), standin("thesis-lds.toml", tmp)
    ref, _ = run(a.sweep, ["lds", lds, "--max", "20000", "--tolerance", "0", "--floor", "0"], os.path.join(tmp, "ref"))
    r = ref["statistics"]
    print("reference (20,000 LDS points): " + ", ".join(f"{s} {r[s]:.4f}" for s in STATS))
    print()
    print("| design | rule | converged at | N | runs | mean | std | skewness | kurtosis | max rel. diff from reference |")
    print("| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for rule, flags in [("any (thesis)", ["--rule", "any"]), ("all (default)", [])]:
        for design, args in [("lattice", ["lattice", lat]), ("LDS", ["lds", lds])]:
            s, _ = run(a.sweep, args + flags, os.path.join(tmp, f"{design}-{rule.split()[0]}"))
            v = s["verdict"]
            st = s["statistics"]
            diff = max(abs(st[k] - r[k]) / abs(r[k]) for k in STATS)
            print(f"| {design} | {rule} | {v['space'] or v['status']} | {v['n'] or '-'} | {s['counts']['done']} | "
                  + " | ".join(f"{st[k]:.4f}" for k in STATS) + f" | {diff * 100:.1f}% |")


if __name__ == "__main__":
    main()
