#!/usr/bin/env python3
"""The tables of docs/study/thesis/README.md from a sweep directory of the thesis study.

    python3 docs/study/thesis/thesis_tables.py DIR [--reference DIR2] [--weights equal|trapezoid] [--save OUT.csv]

DIR is a sweep directory or a record in docs/study/thesis/ (its packed files are unpacked). Works
on a copy of DIR (the report rewrites files). Prints, as Markdown:
- the four MFR statistics of each complete space with their 95 % bootstrap intervals;
- at which N each rule calls the sweep converged: the default ("scaled", 5 %, hold 2) and the
  thesis's ("any", 5 %), as `sweep report --rule ...` judges the same runs;
- from which N every statistic stays within 5 % of its scale of the reference (the last space
  of DIR, or of --reference), the scale being the scaled rule's (mean: max(|mean|, std); std;
  skewness: max(|skewness|, 1); kurtosis);
- the MFR = 0 share, failures by class, cost (core-hours, wall, mean CPU per run).
--weights sets a lattice's statistics' weights (the thesis's equal ones or the default trapezoid
rule) in the copy's sweep.toml; the figures are copied only with the sweep's own weights.
--save keeps the convergence.csv of the default rule (for docs/study/thesis/thesis_compare.py).
Without --weights it copies the report's figures to docs/study/thesis/<name>-figures/; the study's
page keeps the ones it shows.
"""
import csv, glob, gzip, io, json, os, re, shutil, subprocess, sys, tarfile, tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
BIN = os.environ.get("SWEEP_BIN", os.path.join(ROOT, "target/release/sweep"))
STATS = ["mean", "std", "skewness", "kurtosis"]
TOL = 0.05


def report(d, *args):
    subprocess.run([BIN, "report", d, *args], check=False, capture_output=True)
    rows = list(csv.DictReader(open(os.path.join(d, "convergence.csv"))))
    summary = json.load(open(os.path.join(d, "summary.json")))
    return rows, summary


def copy_sweep(src, d):
    """Copy sweep directory or record `src` to `d`, unpacking a record's packed files
    (docs/study/thesis/thesis_study.sh packs manifest.json, joblog.tsv, results.csv and runs/)."""
    shutil.copytree(src, d, ignore=shutil.ignore_patterns("*.liggghts", "dump.*", "*.stl", "*.data", "screen.txt"))
    for f in os.listdir(d):
        if f.endswith(".gz") and not f.endswith(".tar.gz"):
            with gzip.open(os.path.join(d, f)) as z, open(os.path.join(d, f[:-3]), "wb") as out:
                shutil.copyfileobj(z, out)
    parts = sorted(glob.glob(os.path.join(d, "runs.tar.xz.[0-9]*")))
    if parts:
        # One xz stream split into parts of at most 900 kB (thesis_study.sh's pack_runs).
        data = b"".join(open(p, "rb").read() for p in parts)
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:xz") as t:
            t.extractall(d)


def scale(stat, ref):
    m, s, k, ku = (float(ref[x]) for x in STATS)
    return {"mean": max(abs(m), s), "std": s, "skewness": max(abs(k), 1.0), "kurtosis": ku}[stat]


def main():
    src = sys.argv[1]
    ref_dir = sys.argv[sys.argv.index("--reference") + 1] if "--reference" in sys.argv else None
    with tempfile.TemporaryDirectory() as tmp:
        d = os.path.join(tmp, "sweep")
        copy_sweep(src, d)
        weights = sys.argv[sys.argv.index("--weights") + 1] if "--weights" in sys.argv else None
        if weights:
            toml = open(os.path.join(d, "sweep.toml")).read()
            toml = re.sub(r'lattice_weights = "\w+"', f'lattice_weights = "{weights}"', toml)
            open(os.path.join(d, "sweep.toml"), "w").write(toml)
        rows, summary = report(d, "--rule", "scaled", "--tolerance", str(TOL), "--hold", "2")
        if "--save" in sys.argv:
            shutil.copy(os.path.join(d, "convergence.csv"), sys.argv[sys.argv.index("--save") + 1])
        default_at = next((r["n"] for r in rows if r["converged"] == "true"), None)
        any_rows, _ = report(d, "--rule", "any", "--tolerance", str(TOL))
        any_at = next((r["n"] for r in any_rows if r["converged"] == "true"), None)
        ref_rows = rows
        if ref_dir:
            r2 = os.path.join(tmp, "ref")
            copy_sweep(ref_dir, r2)
            ref_rows, _ = report(r2)
        ref = ref_rows[-1]
        print(f"Spaces of {summary['name']} (reference: {ref['space']}, N = {ref['n']}):\n")
        print("| space | N | done | failed | mean [95 %] | std [95 %] | skewness [95 %] | kurtosis [95 %] | all within 5 % of the reference |")
        print("|---|---|---|---|---|---|---|---|---|")
        within_from = None
        for r in rows:
            ok = all(abs(float(r[s]) - float(ref[s])) <= TOL * scale(s, ref) for s in STATS)
            within_from = (within_from or r["n"]) if ok else None
            cells = " | ".join(f"{float(r[s]):.4g} [{float(r[s + '_lo']):.4g}, {float(r[s + '_hi']):.4g}]" for s in STATS)
            print(f"| {r['space']} | {r['n']} | {r['done']} | {r['failed']} | {cells} | {'yes' if ok else 'no'} |")
        print()
        print(f"- default rule (scaled, 5 %, hold 2): converged at N = {default_at or 'not yet'}")
        print(f"- thesis rule (any, 5 %): converged at N = {any_at or 'not yet'}")
        print(f"- every statistic within 5 % of its scale of the reference from N = {within_from or 'never'} on")
        c = summary["counts"]
        t = summary["timing"]
        stats = summary["statistics"] or {}
        mfr = [float(x["mfr"]) for x in csv.DictReader(open(os.path.join(d, "results.csv"))) if x["status"] in ("done", "screened")]
        zero = sum(1 for v in mfr if v == 0.0)
        print(f"- MFR = 0 at {zero} of {len(mfr)} points ({100 * zero / max(len(mfr), 1):.1f} %); "
              f"screened {c.get('screened', 0)}; failed {c.get('failed', 0)} {c.get('failures_by_class', {})}")
        runs = max(t.get("attempts", 0), 1)
        print(f"- cost: {t['core_seconds'] / 3600:.2f} core-hours, wall {t['wall_time_s'] / 3600:.2f} h (runs going), "
              f"{t['core_seconds'] / runs:.2f} core-s per run over {runs} runs")
        em = summary.get("emulator") or {}
        if em:
            cv = em["cross_validation"]
            es = em["statistics"]["statistics"]
            print(f"- emulator ({em['points']} points): LOO RMSE {cv['rmse']:.4f} vs per-point noise {cv['noise_se']:.4f}, "
                  f"Q² {cv['q2']:.3f}, 95 % coverage {cv['coverage95']:.2f}; its mean {es['mean']:.4f}, std {es['std']:.4f}, "
                  f"skewness {es['skewness']:.3f}, kurtosis {es['kurtosis']:.3f}")
        last = rows[-1] if rows else {}
        noise = (summary.get("spaces") or [{}])[-1].get("noise") or {}
        if noise:
            print(f"- per-point noise: {100 * noise['noise_share']:.1f} % of MFR's variance ({noise['points_with_se']} points with an SE)")
        print(f"- sensitivity (first order): " + ", ".join(
            f"{s['parameter']} {s['first_order']:.3f} [{s['lo']:.3f}, {s['hi']:.3f}]" for s in summary.get("sensitivity", [])))
        if stats:
            print(f"- statistics of the last space: mean {stats['mean']:.4f}, std {stats['std']:.4f}, "
                  f"skewness {stats['skewness']:.3f}, kurtosis {stats['kurtosis']:.3f}, median {stats['median']:.4f}")
        if weights:
            return
        figs = os.path.join(d, "report")
        out = os.path.join(ROOT, "docs/study/thesis", summary["name"] + "-figures")
        os.makedirs(out, exist_ok=True)
        for f in os.listdir(figs):
            if f.endswith(".png") and (f.startswith("histogram") or f in ("statistics.png", "scatter.png", "map-mfr-diameter-gap.png", "map-mfr-gap-blade_speed.png")):
                shutil.copy(os.path.join(figs, f), out)
        print(f"\nFigures: {os.path.relpath(out, ROOT)}/")


if __name__ == "__main__":
    main()
