#!/usr/bin/env python3
"""The layers study's figures and tables (docs/study/layers.md), from the records run.sh and
ti64.sh write. Needs matplotlib.

    python3 docs/study/layers/plot.py      # from the repository's root

- plates.png: PS1's 20 layers on plates of 24, 48 and 96 D (those recorded) against the
  experiment, in step;
- gaboriault.png: Gaboriault et al.'s three repeats (min–max band, mean) and our PS1–PS3, in step
  (their layer n against our pass n + 1, compare.py), per layer and per layer group, and
  compare.py's aligned tables;
- ti64-fused.png: the fused bed over passes (the machine answer, its controls, ti64.sh's lattice
  of two layer thicknesses and two blade speeds) — each pass's deposit over the drop (1 once the
  bed is steady) and the powder under the blade over the drop (→ 1 / packing);
- ti64-search.png and ti64-gap.png: the fused bed whose first passes search for the steady
  depth, before the platform gap and on the current scene (ti64-gap.sh) — the powder under the
  blade over the drop and the packing, per pass;
- a Markdown table of each on stdout.
"""
import glob, json, math, os, sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import compare  # noqa: E402  the alignment with the experiment, and its tables


def load(path):
    j = json.load(open(path))
    # `sweep run --json` prints the run's result; a failed run has its passes under `measured`.
    if "layers" in j and j["layers"]:
        return j["layers"], None
    m = j.get("measured") or {}
    return (m.get("layers") if isinstance(m, dict) else None), j.get("reason") or j.get("failed") or "failed"


# Each property set's colour, and its offset along the layers so that error bars do not overlap.
COLOURS = {"PS1": "#e6550d", "PS2": "#3182bd", "PS3": "#31a354"}
OFFSETS = {"PS1": -0.18, "PS2": 0.0, "PS3": 0.18}


def experiment_panels():
    """A figure of two panels with the experiment drawn: per layer its three repeats (min–max as
    a band, their mean as a line), per layer group their mean ± SD. Returns the figure, both
    panels and the experiment's groups."""
    rows = compare.experiment()
    layers = list(range(1, 21))  # their layers; row_of_layer finds each in their file
    reps = [[rows[compare.row_of_layer(n)][i] for n in layers] for i in range(3)]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12.5, 5.0), gridspec_kw={"width_ratios": [2.3, 1]})
    a1.fill_between(layers, [min(v) for v in zip(*reps)], [max(v) for v in zip(*reps)], color="0.6",
                    label="experiment: 3 repeats, min–max")
    a1.plot(layers, [sum(v) / 3 for v in zip(*reps)], color="black", marker="s", markersize=3,
            linewidth=0.8, label="experiment: mean of the repeats")
    exp = compare.experiment_groups(rows)
    a2.errorbar([i - 0.27 for i in range(3)], [e["mean"] for e in exp], yerr=[e["sd"] for e in exp], color="black",
                marker="s", linestyle="none", capsize=4, label="experiment: mean ± SD of the repeats")
    return fig, a1, a2, exp


def finish_panels(fig, a1, a2, exp, title, name):
    """The two panels' axes, legends and title; the figure written to `name` beside this script."""
    a1.set_ylabel("layer relative density (deposit / 100 µm drop)")
    a1.set_ylim(0.25, 0.85)
    a1.grid(alpha=0.3)
    a1.legend(fontsize=7.5, loc="upper left", ncol=2)
    a2.set_xticks(range(3))
    a2.set_xticklabels([f"layer {e['group']}" if e["group"] == "1" else f"layers {e['group']}" for e in exp])
    a2.set_xlim(-0.5, 2.5)
    a2.set_ylim(0.25, 0.85)
    a2.set_ylabel("mean over the group")
    a2.grid(alpha=0.3)
    handles, labels = a2.get_legend_handles_labels()
    keep = {l: h for h, l in zip(handles, labels)}
    a2.legend(keep.values(), keep.keys(), fontsize=7.5, loc="upper left")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, name), dpi=110)


def gaboriault(sets=compare.SETS, plate="1.6 mm", name="gaboriault.png"):
    """Their layers against our passes, in step (compare.py: their layer n is our pass n + 1):
    per layer, and per layer group as compare.py's table has it, for the records `sets`."""
    fig, a1, a2, exp = experiment_panels()
    for record, label in sets:
        p = compare.load_passes(record)
        if not p:
            continue
        c, dx = COLOURS[label], OFFSETS[label]
        values = compare.layer_values(p)
        groups = compare.record_groups(p)
        # A single pass's error: the SD of the record's passes over layers 2–10.
        single = groups[0]["err"]
        ns = sorted(values)
        a1.errorbar([n + dx for n in ns], [values[n] for n in ns], yerr=single, color=c, marker="o",
                    markersize=4.5, linewidth=1.0, capsize=2, elinewidth=0.8,
                    label=f"{label}: pass n + 1 at layer n (± one pass's SD)")
        # Our first pass, into the 200 µm gap: the baseline their script skips, not a layer.
        a1.plot([dx], [p[0]["relative_density"]], marker="o", markerfacecolor="white", color=c, linestyle="none")
        for i, g in enumerate(groups):
            if g["layers"] is None:
                continue
            a2.errorbar([i + 0.06 + 0.8 * dx], [g["mean"]], yerr=[g["err"]], color=c, marker="o", linestyle="none",
                        capsize=4, label=f"{label} ± SE (layer 1: ± one pass's SD)")
    a1.plot([], [], marker="o", markerfacecolor="white", color="0.3", linestyle="none",
            label="our pass 1 over its 200 µm gap: the baseline (no layer)")
    a1.axvline(0.5, color="0.5", linewidth=0.6, linestyle=":")
    a1.set_xticks(range(0, 21))
    a1.set_xticklabels(["base"] + [str(n) for n in range(1, 21)])
    a1.set_xlim(-0.6, 20.6)
    a1.set_xlabel("their layer n  (our pass n + 1)")
    top = a1.secondary_xaxis("top", functions=(lambda x: x + 1, lambda x: x - 1))
    top.set_xticks(range(1, 22, 2))
    top.set_xlabel("our pass")
    finish_panels(fig, a1, a2, exp, f"Ti-6Al-4V 45–106 µm, 100 µm layers, 0.1 m/s, {plate} plate: Gaboriault et "
                  "al. 2025's 20 layers and ours, in step", name)


def gaboriault_seeds(seeds=compare.SEEDS, bed="held 4 D deep", name="gaboriault-seeds.png"):
    """The three sets at their seeds (compare.SEEDS: the held bed; SEEDS_WHOLE: the whole), in step: per layer the seeds' mean ± its SE
    (their SD / √n; one pass's SD where one seed has run), per group the seeds pooled."""
    fig, a1, a2, exp = experiment_panels()
    layers = list(range(1, 21))
    for label, records in seeds:
        runs = [compare.layer_values(p) for p in map(compare.load_passes, records) if p]
        if not runs:
            continue
        c, dx = COLOURS[label], OFFSETS[label]
        single = compare.record_groups(compare.load_passes(records[0]))[0]["err"]
        ns = [n for n in layers if all(n in r for r in runs)]
        ys = [compare.mean([r[n] for r in runs]) for n in ns]
        es = [compare.sd([r[n] for r in runs]) / math.sqrt(len(runs)) if len(runs) > 1 else single for n in ns]
        a1.errorbar([n + dx for n in ns], ys, yerr=es, color=c, marker="o", markersize=4.5, linewidth=1.0, capsize=2,
                    elinewidth=0.8, label=f"{label}: mean of {len(runs)} seeds ± SE" if len(runs) > 1 else f"{label}: 1 seed ± one pass's SD")
        for i, g in enumerate(compare.pooled_groups(records)):
            if g is not None:
                a2.errorbar([i + 0.06 + 0.8 * dx], [g["mean"]], yerr=[g["err"]], color=c, marker="o",
                            linestyle="none", capsize=4, label=f"{label}, seeds pooled ± SE")
    a1.set_xticks(layers)
    a1.set_xlim(0.4, 20.6)
    a1.set_xlabel("their layer n  (our pass n + 1)")
    finish_panels(fig, a1, a2, exp, f"Ti-6Al-4V 45–106 µm, 100 µm layers, 0.1 m/s, 1.6 mm plate, {bed}: "
                  "Gaboriault et al. 2025's 20 layers and ours over seeds, in step", name)


VARIANTS = {"flat": "flat blade", "gamma0": "no cohesion", "halfdose": "half the dose", "depth12": "depth 12 D",
            "dt0.165": "timestep halved", "plate20": "plate 20 D", "plate80": "plate 80 D", "seed2": "seed 2",
            "back": "the blade's back cut (0.1 D)"}


def pretty(label):
    """'50um-0.1-gamma0' → '50 µm, 0.1 m/s, no cohesion'."""
    t, v, *rest = label.split("-")
    if rest and rest[0] == "gap":
        return ", ".join([t.replace("um", " µm"), v + " m/s"] + [VARIANTS.get(r, r) for r in rest[1:]])
    # The sweep's own blade is round; variants say what they change.
    if rest and rest[0].startswith("search"):
        # The search's records: the round blade unless a variant follows.
        return ", ".join([t.replace("um", " µm"), v + " m/s", f"search {rest[0][6:]}"]
                         + [VARIANTS.get(r, r) for r in rest[1:]])
    blade = [] if "flat" in rest else ["round blade"]
    return ", ".join([t.replace("um", " µm"), v + " m/s"] + blade + [VARIANTS.get(r, r) for r in rest])


def ti64_runs():
    """(name, label, series, failed, cpu) of the machine answer's records."""
    out = []
    for path in sorted(glob.glob(os.path.join(HERE, "record", "ti64-*.json"))):
        series, failed = load(path)
        if not series:
            continue
        j = json.load(open(path))
        cpu = j.get("cpu_time") or (j.get("measured") or {}).get("cpu_time") or float("nan")
        name = os.path.basename(path)[5:-5]
        out.append((name, pretty(name), series, failed, cpu))
    return out


def ti64_laid(runs):
    """The 50 µm point laid layer on layer from the bare plate: ti64-fused.png and its table."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.4))
    print()
    print("| case | steady | deposit, last 6 passes ± SE (µm) | over the drop | powder under the tip at the last pass (µm) | packing, last 6 | covered, last 6 | CPU s |")
    print("|---|---|---|---|---|---|---|---|")
    for _, label, series, failed, cpu in runs:
        p = series["passes"]
        t = series["layer_thickness_m"]
        ks = [q["k"] for q in p]
        a1.plot(ks, [q["deposit_m"] / t for q in p], marker=".", label=label)
        a2.plot(ks, [q["effective_thickness_m"] / t for q in p], marker=".", label=label)
        last = p[-6:]
        dep = [q["deposit_m"] * 1e6 for q in last]
        m = sum(dep) / len(dep)
        se = (sum((x - m) ** 2 for x in dep) / (len(dep) - 1) / len(dep)) ** 0.5
        pk = sum(q["packing"] for q in last) / len(last)
        cov = sum(q["covered_fraction"] for q in last) / len(last)
        steady = f"from pass {series['steady_from']}" if not failed else "no"
        print(f"| {label} | {steady} | {m:.1f} ± {se:.1f} | {m * 1e-6 / t:.2f} | "
              f"{p[-1]['effective_thickness_m'] * 1e6:.0f} | {pk:.3f} | {cov:.2f} | {cpu:.0f} |")
    a1.axhline(1.0, color="black", linewidth=0.8)
    finish(fig, {a1: "deposit / layer thickness (1: the bed keeps pace)",
                 a2: "powder under the blade / layer thickness"}, "pass",
           "Ti-6Al-4V 15–45 µm on a fused bed: a steady bed deposits the layer thickness each pass",
           "ti64-fused.png")


def finish(fig, ylabels, xlabel, title, name):
    """Label, grid and save a figure of passes."""
    for a, y in ylabels.items():
        a.set_ylabel(y)
        a.set_xlabel(xlabel)
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, name), dpi=110)


def ti64_searched(runs, drawn, title, name):
    """The points whose first passes searched for the steady depth: a figure of those `drawn`
    picks, and the steady layer of each (mean ± SE over the passes from `steady_from`)."""
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.4))
    print()
    print("| case | passes (search) | steady from | packing ± SE | powder under the tip ± SE (µm) | over the drop | deposit over the drop ± SE | covered | CPU s | CPU s a pass |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for case, label, series, failed, cpu in runs:
        p = series["passes"]
        t = series["layer_thickness_m"]
        search = sum(1 for q in p if q.get("search"))
        if drawn(case):
            line = a1.plot([q["k"] for q in p], [q["effective_thickness_m"] / t for q in p], marker=".", label=label)[0]
            a2.plot([q["k"] for q in p], [q["packing"] for q in p], marker=".", color=line.get_color(), label=label)
            for a, key in ((a1, "effective_thickness_m"), (a2, "packing")):
                s = [q for q in p if q.get("search")]
                a.plot([q["k"] for q in s], [q[key] / (t if key != "packing" else 1) for q in s], "o",
                       mfc="white", color=line.get_color())
        steady = f"{series['steady_from']}" if not failed else f"not steady ({series['steady_from']})"
        print(f"| {label} | {len(p)} ({search}) | {steady} | {series['packing']:.3f} ± {series['packing_se']:.3f} | "
              f"{series['effective_thickness_m'] * 1e6:.0f} ± {series['effective_thickness_se_m'] * 1e6:.1f} | "
              f"{series['effective_thickness_m'] / t:.1f} | {series['relative_density']:.3f} ± {series['relative_density_se']:.3f} | "
              f"{series['covered_fraction']:.2f} | {cpu:.0f} | {cpu / len(p):.0f} |")
    finish(fig, {a1: "powder under the blade / layer thickness", a2: "packing of the pass's layer"},
           "pass (open: searching for the steady depth)", title, name)


def ti64():
    runs = ti64_runs()
    laid = [r for r in runs if "search" not in r[0] and "gap" not in r[0]]
    searched = [r for r in runs if "search" in r[0]]
    gap = [r for r in runs if "gap" in r[0]]
    if laid:
        ti64_laid(laid)
    if searched:
        # The machine's cases (and one at half the dose); the numerical variants and the other
        # half-dose runs only in the table.
        ti64_searched(searched, lambda n: n.endswith("search6") or n == "50um-0.1-search6-halfdose",
                      "Ti-6Al-4V 15–45 µm on a fused bed, round blade: searching for the steady layer "
                      "(before the platform gap)", "ti64-search.png")
    if gap:
        # The machine's cases on the current scene; the second seed and the numerical checks only
        # in the table.
        ti64_searched(gap, lambda n: n.endswith("-gap"),
                      "Ti-6Al-4V 15–45 µm on a fused bed, round blade, the current scene: the steady layer",
                      "ti64-gap.png")


def loose():
    """PS1's loose bed at two blade speeds and two layer thicknesses: loose.png and its table."""
    cases = [("PS1", "100 µm, 0.1 m/s"), ("PS1-0.2", "100 µm, 0.2 m/s"), ("PS1-150um", "150 µm, 0.1 m/s")]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.4))
    print()
    print("| case | steady from | layer relative density ± SE | bed relative density, last 3 passes | powder under the blade (µm) | packing ± SE | covered | CPU s |")
    print("|---|---|---|---|---|---|---|---|")
    for name, label in cases:
        path = os.path.join(HERE, "record", name + ".json")
        if not os.path.exists(path):
            continue
        series, failed = load(path)
        p = series["passes"]
        ks = [q["k"] for q in p]
        line = a1.plot(ks, [q["relative_density"] for q in p], marker=".", label=label)[0]
        s, m, se = series["steady_from"], series["relative_density"], series["relative_density_se"]
        a1.fill_between([s, len(p)], [m - se] * 2, [m + se] * 2, color=line.get_color(), alpha=0.2)
        bed = [(q["k"], q["bed_relative_density"]) for q in p if q.get("bed_relative_density") is not None]
        a2.plot([k for k, _ in bed], [b for _, b in bed], marker=".", color=line.get_color(), label=label)
        last = [b for _, b in bed[-3:]]
        cpu = json.load(open(path)).get("cpu_time") or float("nan")
        print(f"| {label} | {s}{'' if series['steady'] else ' (not steady)'} | {m:.3f} ± {se:.3f} | "
              f"{min(last):.3f}–{max(last):.3f} | {series['effective_thickness_m'] * 1e6:.0f} ± "
              f"{series['effective_thickness_se_m'] * 1e6:.0f} | {series['packing']:.3f} ± {series['packing_se']:.3f} | "
              f"{series['covered_fraction']:.2f} | {cpu:.0f} |")
    finish(fig, {a1: "layer relative density (deposit / drop)", a2: "bed relative density (all passes so far)"},
           "pass", "Ti-6Al-4V 45–106 µm (PS1) on a loose bed: the layer and the bed over passes", "loose.png")


def plates():
    """PS1's 20 layers on plates of 24, 48 and 96 D against the experiment, in step (compare.PLATES;
    each plate once its run is recorded)."""
    rows = compare.experiment()
    layers = list(range(1, 21))
    reps = [[rows[compare.row_of_layer(n)][i] for n in layers] for i in range(3)]
    fig, ax = plt.subplots(figsize=(10, 4.6))
    ax.fill_between(layers, [min(v) for v in zip(*reps)], [max(v) for v in zip(*reps)], color="0.6",
                    label="experiment: 3 repeats, min–max")
    ax.plot(layers, [sum(v) / 3 for v in zip(*reps)], color="black", marker="s", markersize=3, linewidth=0.8,
            label="experiment: mean of the repeats")
    colours = ["#fdae6b", "#e6550d", "#7f2704"]
    for (record, label), c, dx in zip(compare.PLATES, colours, (-0.15, 0.0, 0.15)):
        p = compare.load_passes(record)
        if not p:
            continue
        values = compare.layer_values(p)
        single = compare.record_groups(p)[1]["err"] * math.sqrt(compare.record_groups(p)[1]["n"])
        ns = sorted(values)
        ax.errorbar([n + dx for n in ns], [values[n] for n in ns], yerr=single, color=c, marker="o", markersize=4,
                    linewidth=1.0, capsize=2, elinewidth=0.8, label=f"{label} (± one pass's SD)")
    ax.set_xticks(layers)
    ax.set_xlim(0.4, 20.6)
    ax.set_ylim(0.3, 0.8)
    ax.set_xlabel("their layer n  (our pass n + 1)")
    ax.set_ylabel("layer relative density")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right", ncol=2)
    ax.set_title("PS1, 100 µm layers, 0.1 m/s, bed held 4 D under its top: the plate's length "
                 "against Gaboriault et al. 2025's layers", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(HERE, "plates.png"), dpi=110)


if __name__ == "__main__":
    plates()
    gaboriault()
    gaboriault(compare.SETS48, "3.2 mm", "gaboriault-48.png")
    gaboriault_seeds()
    gaboriault_seeds(compare.SEEDS_WHOLE, "the whole bed moving", "gaboriault-whole.png")
    compare.main_tables()
    loose()
    ti64()
