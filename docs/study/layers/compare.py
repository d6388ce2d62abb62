#!/usr/bin/env python3
"""Gaboriault et al. 2025's measured layers against our passes, in step (docs/study/layers.md).

    python3 docs/study/layers/compare.py              # the aligned tables, Markdown, on stdout
    python3 docs/study/layers/compare.py --self-test  # the alignment checked (tests/it/layers_compare.rs)

**The alignment.** Their `post_processing/post_rel_density.py` measures the plate after every
blade pass and skips the first (`if index ==0: continue`): the pass into the first gap (the
plate's 100 µm drop and the blade's 100 µm clearance) is a baseline. Their layer 1 is the second
pass's added volume over δn × the plate's area, and `graph_rel_density.py` plots it at layer 1
beside `experimental.data`'s row 0 (`layer_number + 1`). So their layer n — the file's row n − 1
— stands against our pass n + 1: `pass_of_layer` and `row_of_layer` below, and nowhere else.

**What is compared.** Per layer group (1; 2–10; 11–20): the experiment's three repeats, each
averaged over the group, as mean ± SD of the three; ours, per record, the mean of our passes
that are the group's layers ± its SE (SD/√n over those passes; a loose bed's passes are not
correlated, docs/study/layers.md). A group of one layer has one pass: its error is a single
pass's scatter, the SD of the same record's passes over layers 2–10. A group our passes cover
only in part is averaged over the layers covered and says which; one they do not reach is n/a.

**The self-test** feeds the experiment's own rows to the records' code as if they were our
passes — row n − 1 as pass n + 1 (`--feed-shift`, 1 by default, says by how much a row is moved
on: row n − 1 → pass n + shift), pass 1 a baseline of 0 — and checks that every group's mean comes
back exactly as the experiment's. It prints JSON and exits 1 when a mean differs.

Needs only the standard library (plot.py draws the figure from the same functions).
"""
import argparse, json, math, os, sys

HERE = os.path.dirname(os.path.abspath(__file__))

# Their layer groups: the first layer; the plateau; the densification (the paper's subject).
GROUPS = [("1", 1, 1), ("2–10", 2, 10), ("11–20", 11, 20)]
PLATEAU = (2, 10)

# The records of their case (sweeps/layers-gaboriault.toml): the three property sets over all 20
# layers (21 passes on the 24 D plate, the bed held 4 D under the top and shed beneath,
# twenty.sh), then the first runs of 8 passes (the whole bed moving) and the variants of the same
# case that measure its numerical and seed error.
SETS = [("twenty-PS1-plate24-freeze4-bury", "PS1"), ("twenty-PS2-plate24-freeze4-bury", "PS2"),
        ("twenty-PS3-plate24-freeze4-bury", "PS3")]
# The same on the 48 D plate (3.2 mm): a pass's scatter halved.
SETS48 = [("twenty-PS1-plate48-freeze4-bury", "PS1"), ("twenty-PS2-plate48-freeze4-bury", "PS2"),
          ("twenty-PS3-plate48-freeze4-bury", "PS3")]
EIGHT = [("PS1", "PS1, 8 passes"), ("PS2", "PS2, 8 passes"), ("PS3", "PS3, 8 passes")]
VARIANTS = [("PS1-plate12", "PS1, plate halved (12 D)"), ("PS2-seed2", "PS2, seed 2")]
# The plate's length for the 20 layers (issue 68's ladder towards their 10.4 mm L1): PS1 on the
# same hold at 24 D (1.6 mm, SETS), 48 D (3.2 mm) and 96 D (6.4 mm), as far as each has run.
PLATES = [("twenty-PS1-plate24-freeze4-bury", "PS1, 24 D (1.6 mm)"),
          ("twenty-PS1-plate48-freeze4-bury", "PS1, 48 D (3.2 mm)"),
          ("twenty-PS1-plate96-freeze4-bury", "PS1, 96 D (6.4 mm)")]
PLATES_PS2 = [("twenty-PS2-plate24-freeze4-bury", "PS2, 24 D (1.6 mm)"),
              ("twenty-PS2-plate48-freeze4-bury", "PS2, 48 D (3.2 mm)")]
PLATES_PS3 = [("twenty-PS3-plate24-freeze4-bury", "PS3, 24 D (1.6 mm)"),
              ("twenty-PS3-plate48-freeze4-bury", "PS3, 48 D (3.2 mm)")]
# The loose bed held 4 D under the top and shed beneath (SETS) against the whole bed moving, on
# one deck (PS1, 24 D, 21 passes).
HOLD = [("twenty-PS1-plate24-freeze4-bury", "PS1, held 4 D and shed"),
        ("twenty-PS1-plate24-now", "PS1, the whole bed moving")]
# The same pair at a second seed (`seed = 2`: the doses' insertion seeds).
HOLD2 = [("twenty-PS1-plate24-freeze4-bury-seed2", "PS1 seed 2, held 4 D and shed"),
         ("twenty-PS1-plate24-now-seed2", "PS1 seed 2, the whole bed moving")]
# ... and at a third (the whole bed's run had 15 of 21 passes at the stop).
HOLD3 = [("twenty-PS1-plate24-freeze4-bury-seed3", "PS1 seed 3, held 4 D and shed"),
         ("twenty-PS1-plate24-now-seed3", "PS1 seed 3, the whole bed moving")]
# The scene's numerical choices at PS1 (24 D, the 4 D hold): the timestep halved (0.33 → 0.165
# Rayleigh times) and the periodic depth doubled (6 → 12 D), 11 passes each (their layers 1–10).
# Each set at three seeds on the study's bed (24 D, held 4 D; `seed = 2` and `3`: seeds.sh),
# pooled per group (inverse variance over the seeds' group means, each ± its SE).
SEEDS = [("PS1", ["twenty-PS1-plate24-freeze4-bury", "twenty-PS1-plate24-freeze4-bury-seed2",
                  "twenty-PS1-plate24-freeze4-bury-seed3"]),
         ("PS2", ["twenty-PS2-plate24-freeze4-bury", "twenty-PS2-plate24-freeze4-bury-seed2",
                  "twenty-PS2-plate24-freeze4-bury-seed3"]),
         ("PS3", ["twenty-PS3-plate24-freeze4-bury", "twenty-PS3-plate24-freeze4-bury-seed2",
                  "twenty-PS3-plate24-freeze4-bury-seed3"])]
# The same on the whole bed moving (no hold: the hold reads the steady layer 0.027 ± 0.012 low,
# three seeds pooled), as far as each set has run (`TAG=now twenty.sh PSn`, `seed = 2`, `3`).
SEEDS_WHOLE = [("PS1", ["twenty-PS1-plate24-now", "twenty-PS1-plate24-now-seed2", "twenty-PS1-plate24-now-seed3"]),
               ("PS2", ["twenty-PS2-plate24-now", "twenty-PS2-plate24-now-seed2", "twenty-PS2-plate24-now-seed3"]),
               ("PS3", ["twenty-PS3-plate24-now", "twenty-PS3-plate24-now-seed2", "twenty-PS3-plate24-now-seed3"])]
# The loose bed's dose doubled (`supply_factor = 2`, 11 passes: their layers 1–10) against the
# whole bed's seed 1 over the same layers: does a pass run short of powder?
SUPPLY = [("twenty-PS1-plate24-now", "PS1 whole bed, seed 1"),
          ("twenty-PS1-plate24-passes11-now-supply2", "PS1 whole bed, the dose doubled")]
NUMERICS = [("twenty-PS1-plate24-freeze4-bury", "PS1 as shipped"),
            ("twenty-PS1-plate24-freeze4-passes11-bury-dt0.165", "timestep halved"),
            ("twenty-PS1-plate24-freeze4-passes11-bury-depth12", "depth doubled (12 D)")]


def pass_of_layer(n):
    """Our pass that stands against their layer n: their first pass is a baseline they skip."""
    return n + 1


def row_of_layer(n):
    """experimental.data's row (its `Layer_number`) that holds their layer n."""
    return n - 1


def mean(xs):
    s = 0.0
    for x in xs:
        s += x
    return s / len(xs)


def sd(xs):
    """Sample standard deviation (n − 1)."""
    m = mean(xs)
    return math.sqrt(sum((x - m) ** 2 for x in xs) / (len(xs) - 1))


def experiment(path=os.path.join(HERE, "experimental.data")):
    """{row: [R1, R2, R3]} from their file."""
    rows = {}
    for line in open(path):
        if line.startswith("#") or line.startswith("Layer"):
            continue
        k, *r = line.split()
        rows[int(k)] = [float(x) for x in r]
    return rows


def experiment_repeat_means(rows, first, last):
    """Each repeat's mean over their layers first..last, read from the rows that hold them."""
    return [mean([rows[row_of_layer(n)][i] for n in range(first, last + 1)]) for i in range(3)]


def experiment_groups(rows):
    """Per group: the three repeats' means, their mean and SD."""
    out = []
    for name, a, b in GROUPS:
        reps = experiment_repeat_means(rows, a, b)
        out.append({"group": name, "layers": [a, b], "repeats": reps, "mean": mean(reps), "sd": sd(reps)})
    return out


def layer_values(passes):
    """{their layer n: our value} from a record's passes ({k, relative_density}); our pass 1,
    the baseline, stands against no layer. A pass's relative density after the first is its
    deposit over the drop, as theirs is."""
    by_pass = {q["k"]: q["relative_density"] for q in passes}
    out = {}
    n = 1
    while pass_of_layer(n) in by_pass:
        out[n] = by_pass[pass_of_layer(n)]
        n += 1
    return out


def record_groups(passes):
    """Per group: our mean over the layers our passes reach, its error, and which layers."""
    values = layer_values(passes)
    a, b = PLATEAU
    plateau = [values[n] for n in range(a, b + 1) if n in values]
    single = sd(plateau) if len(plateau) > 1 else float("nan")
    out = []
    for name, a, b in GROUPS:
        covered = [n for n in range(a, b + 1) if n in values]
        if not covered:
            out.append({"group": name, "layers": None})
            continue
        xs = [values[n] for n in covered]
        err = sd(xs) / math.sqrt(len(xs)) if len(xs) > 1 else single
        out.append({"group": name, "layers": [covered[0], covered[-1]], "n": len(xs), "mean": mean(xs),
                    "err": err, "err_kind": "SE" if len(xs) > 1 else "one pass's SD"})
    return out


def load_passes(label):
    path = os.path.join(HERE, "record", label + ".json")
    if not os.path.exists(path):
        return None
    j = json.load(open(path))
    layers = j.get("layers") or (j.get("measured") or {}).get("layers")
    return layers["passes"] if layers else None


def cell(g, e, rows):
    """One record's cell of the table: mean ± error, the layers when only some of the group's,
    and how many combined SE it lies from the experiment over the same layers."""
    if g["layers"] is None:
        return "n/a (not run)"
    a, b = g["layers"]
    reps = experiment_repeat_means(rows, a, b)
    exp_se = sd(reps) / math.sqrt(3)
    z = (g["mean"] - mean(reps)) / math.sqrt(g["err"] ** 2 + exp_se ** 2)
    part = "" if [a, b] == e["layers"] else f", layers {a}–{b}" if a != b else f", layer {a}"
    return f"{g['mean']:.3f} ± {g['err']:.3f}{part} ({z:+.1f})"


def table(labels, rows):
    exp = experiment_groups(rows)
    recs = [(name, load_passes(label)) for label, name in labels]
    recs = [(n, record_groups(p)) for n, p in recs if p]
    print("| their layers | our passes | experiment, mean ± SD of 3 repeats | "
          + " | ".join(n for n, _ in recs) + " |")
    print("|---|---|---|" + "---|" * len(recs))
    for i, e in enumerate(exp):
        a, b = e["layers"]
        ps = f"{pass_of_layer(a)}" if a == b else f"{pass_of_layer(a)}–{pass_of_layer(b)}"
        print(f"| {e['group']} | {ps} | {e['mean']:.3f} ± {e['sd']:.3f} | "
              + " | ".join(cell(g[i], e, rows) for _, g in recs) + " |")
    covered = {tuple(g[i]["layers"]) for _, g in recs for i in range(len(GROUPS))
               if g[i]["layers"] and g[i]["layers"] != exp[i]["layers"]}
    for a, b in sorted(covered):
        reps = experiment_repeat_means(rows, a, b)
        print(f"\nThe experiment over layers {a}–{b} only: {mean(reps):.3f} ± {sd(reps):.3f} (SD of 3 repeats).")


def moves(labels):
    """Each record's group means against the first record's, over the layers both reach: the
    move ± combined SE (how far a numerical choice or a cut moved the answer)."""
    recs = [(name, load_passes(label)) for label, name in labels]
    recs = [(n, layer_values(p)) for n, p in recs if p]
    if len(recs) < 2:
        return
    base_name, base = recs[0]
    print(f"| their layers | {base_name} | " + " | ".join(f"{n}: move (combined SE)" for n, _ in recs[1:]) + " |")
    print("|---|---|" + "---|" * (len(recs) - 1))
    for name, a, b in GROUPS[1:]:
        cells = []
        for _, v in recs[1:]:
            both = [n for n in range(a, b + 1) if n in v and n in base]
            if len(both) < 2:
                cells.append("n/a")
                continue
            xs, ys = [v[n] for n in both], [base[n] for n in both]
            se = math.sqrt(sd(xs) ** 2 / len(xs) + sd(ys) ** 2 / len(ys))
            d = mean(xs) - mean(ys)
            part = f", layers {both[0]}–{both[-1]}" if [both[0], both[-1]] != [a, b] else ""
            cells.append(f"{mean(xs):.3f}, {d:+.3f} ± {se:.3f} ({d / se:+.1f}){part}")
        ref = [base[n] for n in range(a, b + 1) if n in base]
        print(f"| {name} | {mean(ref):.3f} ± {sd(ref) / math.sqrt(len(ref)):.3f} | " + " | ".join(cells) + " |")


def steady_moves(pairs):
    """The steady layer (the point's answer: its relative density ± SE over the passes MSER
    keeps) of each (held, whole) pair, the whole bed's minus the held one's ± combined SE, and
    the pairs pooled (inverse-variance)."""
    ws, wd = 0.0, 0.0
    for held, whole in pairs:
        recs = []
        for label in (held, whole):
            path = os.path.join(HERE, "record", label + ".json")
            if not os.path.exists(path):
                break
            j = json.load(open(path))
            recs.append((j["relative_density"], j["relative_density_se"]))
        if len(recs) < 2:
            print(f"| {held} | not finished |")
            continue
        (h, hse), (w, wse) = recs
        d, se = w - h, math.sqrt(hse ** 2 + wse ** 2)
        ws, wd = ws + 1 / se ** 2, wd + d / se ** 2
        print(f"| {whole} − {held} | {h:.3f} ± {hse:.3f} | {w:.3f} ± {wse:.3f} | {d:+.3f} ± {se:.3f} ({d / se:+.1f}) |")
    if ws:
        print(f"| pooled | | | {wd / ws:+.3f} ± {1 / math.sqrt(ws):.3f} ({wd / ws * math.sqrt(ws):+.1f}) |")


def pooled_groups(labels):
    """Per group: the inverse-variance mean of the records' group means (each ± its SE, a
    single layer's ± one pass's SD), and how many records were pooled; None where none ran."""
    recs = [record_groups(p) for p in map(load_passes, labels) if p]
    out = []
    for i, (name, a, b) in enumerate(GROUPS):
        gs = [g[i] for g in recs if g[i]["layers"] == [a, b]]
        if not gs:
            out.append(None)
            continue
        w = sum(1 / g["err"] ** 2 for g in gs)
        out.append({"mean": sum(g["mean"] / g["err"] ** 2 for g in gs) / w, "err": 1 / math.sqrt(w), "n": len(gs)})
    return out


def pooled_table(sets, rows):
    """Each set's group means pooled over its seeds against the experiment (combined SE), then
    each pair of sets' difference."""
    exp = experiment_groups(rows)
    pooled = [(name, pooled_groups(labels)) for name, labels in sets]
    print("| their layers | our passes | experiment, mean ± SD of 3 repeats | "
          + " | ".join(f"{n} (seeds pooled)" for n, _ in pooled) + " |")
    print("|---|---|---|" + "---|" * len(pooled))
    for i, e in enumerate(exp):
        a, b = e["layers"]
        ps = f"{pass_of_layer(a)}" if a == b else f"{pass_of_layer(a)}–{pass_of_layer(b)}"
        exp_se = e["sd"] / math.sqrt(3)
        cells = []
        for _, g in pooled:
            if g[i] is None:
                cells.append("n/a")
                continue
            z = (g[i]["mean"] - e["mean"]) / math.sqrt(g[i]["err"] ** 2 + exp_se ** 2)
            cells.append(f"{g[i]['mean']:.3f} ± {g[i]['err']:.3f}, {g[i]['n']} seed{'s' if g[i]['n'] > 1 else ''} ({z:+.1f})")
        print(f"| {e['group']} | {ps} | {e['mean']:.3f} ± {e['sd']:.3f} | " + " | ".join(cells) + " |")
    print()
    print("| their layers | " + " | ".join(f"{x} − {y}" for (x, _), (y, _) in pairs(pooled)) + " |")
    print("|---|" + "---|" * len(pairs(pooled)))
    for i, e in enumerate(exp):
        cells = []
        for (_, gx), (_, gy) in pairs(pooled):
            if gx[i] is None or gy[i] is None:
                cells.append("n/a")
                continue
            d, se = gx[i]["mean"] - gy[i]["mean"], math.hypot(gx[i]["err"], gy[i]["err"])
            cells.append(f"{d:+.3f} ± {se:.3f} ({d / se:+.1f})")
        print(f"| {e['group']} | " + " | ".join(cells) + " |")


def pairs(xs):
    return [(xs[j], xs[i]) for i in range(len(xs)) for j in range(i + 1, len(xs))]


def self_test(shift):
    """The experiment's rows fed as our passes (row n − 1 → pass n + shift; pass 1 a baseline of
    0 when shift is 1); every group's mean must come back as the experiment's, exactly."""
    rows = experiment()
    exp = experiment_groups(rows)
    out = {"shift": shift, "repeats": [], "ok": True}
    for i in range(3):
        passes = [{"k": 1, "relative_density": 0.0}] if shift == 1 else []
        for row in sorted(rows):
            k = (row + 1) + shift  # row n − 1 holds layer n = row + 1
            if k >= 1 and not any(q["k"] == k for q in passes):
                passes.append({"k": k, "relative_density": rows[row][i]})
        fed = record_groups(passes)
        groups = []
        for f, e in zip(fed, exp):
            same = f["layers"] == e["layers"] and f["mean"] == e["repeats"][i]
            out["ok"] &= same
            groups.append({"group": e["group"], "layers": e["layers"], "fed": f.get("mean"),
                           "fed_layers": f["layers"], "experiment": e["repeats"][i], "same": same})
        out["repeats"].append({"repeat": f"R{i + 1}", "groups": groups})
    out["experiment"] = [{"group": e["group"], "mean": e["mean"], "sd": e["sd"]} for e in exp]
    print(json.dumps(out, indent=1, ensure_ascii=False))
    return out["ok"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--self-test", action="store_true", help="check the alignment on the experiment's own rows")
    ap.add_argument("--feed-shift", type=int, default=1,
                    help="self-test: feed row n − 1 as pass n + SHIFT (1 is the alignment; 0 must fail)")
    args = ap.parse_args()
    if args.self_test:
        sys.exit(0 if self_test(args.feed_shift) else 1)
    main_tables()


def main_tables():
    """The aligned tables of docs/study/layers.md."""
    rows = experiment()
    print("Their layer n against our pass n + 1; ours: mean ± SE over the passes (a single pass: ± the "
          "SD of that record's passes over layers 2–10); in brackets, combined SE from the experiment "
          "over the same layers.\n")
    table(SETS, rows)
    print()
    pooled_table(SEEDS, rows)
    print()
    pooled_table(SEEDS_WHOLE, rows)
    print()
    table(SETS48, rows)
    print()
    table(PLATES, rows)
    print()
    table(PLATES_PS2, rows)
    print()
    table(PLATES_PS3, rows)
    print()
    table(HOLD, rows)
    print()
    moves(HOLD)
    print()
    table(HOLD2, rows)
    print()
    moves(HOLD2)
    print()
    table(HOLD3, rows)
    print()
    moves(HOLD3)
    print()
    print("| the steady layer | held | whole | whole − held (combined SE) |\n|---|---|---|---|")
    steady_moves([(HOLD[0][0], HOLD[1][0]), (HOLD2[0][0], HOLD2[1][0]), (HOLD3[0][0], HOLD3[1][0])])
    print()
    table(SUPPLY, rows)
    print()
    moves(SUPPLY)
    print()
    table(NUMERICS, rows)
    print()
    moves(NUMERICS)
    print()
    table(EIGHT, rows)
    print()
    table([("PS1", "PS1 (24 D, seed 1)"), VARIANTS[0], ("PS2", "PS2 (seed 1)"), VARIANTS[1]], rows)


if __name__ == "__main__":
    main()
