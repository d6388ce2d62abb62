#!/usr/bin/env python3
"""Where a conveyor point's CPU goes, from the LIGGGHTS logs of a sweep directory's runs.

    python3 docs/study/point-cost/shares.py SWEEP_DIR [SWEEP_DIR ...]

Per directory, medians over its finished runs of: the steps spent before the window (warm-up
blocks and the blocks MSER cut) against the window's; the engine's own split of its loop time
(pair forces, neighbour lists, communication, output, the rest: fixes such as the blade mesh,
the walls and the heap's top-up); the time outside the loops (start-up, reading the data file,
and the setup LIGGGHTS does before each block's `run`); and the atoms: the powder and the
substrate's spheres at the end.
"""
import json, os, re, statistics, sys

TIMERS = {"Pair": "pair", "Neigh": "neigh", "Comm": "comm", "Outpt": "output", "Other": "other"}


def one(run):
    log = open(os.path.join(run, "log.liggghts")).read()
    r = json.load(open(os.path.join(run, "result.json")))
    st = r["steady_state"]
    loops = [float(x) for x in re.findall(r"Loop time of ([0-9.eE+-]+) on", log)]
    t = {v: sum(float(x) for x in re.findall(rf"^{k}\s+time \(%\) = ([0-9.eE+-]+)", log, re.M))
         for k, v in TIMERS.items()}
    atoms = [int(x) for x in re.findall(r"for \d+ steps with (\d+) atoms", log)]
    sub = re.search(r"(\d+) atoms in group substrate", log)
    # The series holds every block; the first transient_blocks (the deck's warm-up and MSER's cut)
    # come before the window.
    before, total = st["transient_blocks"], len(st["block_mfr"])
    # The engine's timers are wall clock, as is the run's wall time (a loaded machine stretches
    # both alike); the shares are of the wall time, the cost quoted is CPU.
    cpu, wall = r["cpu_time"], r["wall_time"]
    loop = sum(loops)
    return dict(cpu=cpu, before=before / total, runs=len(loops), outside=(wall - loop) / wall,
                per_run_ms=1e3 * (wall - loop) / max(len(loops), 1),
                **{k: v / wall for k, v in t.items()},
                atoms=atoms[-1] if atoms else 0, substrate=int(sub.group(1)) if sub else 0,
                us_per_atom_step=1e6 * loop / max(r["steps"] * (atoms[-1] if atoms else 1), 1))


def main():
    print("| directory | runs | CPU s | steps before the window | pair | neigh | other (fixes) | comm + output "
          "| outside the loops | per block's `run`, ms | atoms (substrate) | µs per atom-step |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for d in sys.argv[1:]:
        rows = []
        for h in sorted(os.listdir(os.path.join(d, "runs"))):
            run = os.path.join(d, "runs", h)
            if os.path.exists(os.path.join(run, "result.json")) and os.path.exists(os.path.join(run, "log.liggghts")):
                try:
                    rows.append(one(run))
                except (KeyError, AttributeError, TypeError):
                    pass
        if not rows:
            continue
        m = lambda k: statistics.median(x[k] for x in rows)
        pct = lambda k: f"{100 * m(k):.0f} %"
        print(f"| {os.path.basename(d.rstrip('/'))} | {len(rows)} | {m('cpu'):.2f} | {pct('before')} | {pct('pair')} "
              f"| {pct('neigh')} | {pct('other')} | {100 * (m('comm') + m('output')):.0f} % | {pct('outside')} "
              f"| {m('per_run_ms'):.1f} | {m('atoms'):.0f} ({m('substrate'):.0f}) | {m('us_per_atom_step'):.2f} |")


if __name__ == "__main__":
    main()
