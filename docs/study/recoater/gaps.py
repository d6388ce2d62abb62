#!/usr/bin/env python3
"""MFR against the gap at a fixed heap: the Beverloo-like line and the monolayer ceiling.

    python3 docs/study/recoater/gaps.py RUNS_DIR [MIN_GAP_D]

Each point (a run directory with result.json) gives the layer's packing φ and its SE. The mass
deposited per width and travel over ρ is φ·t (t the layer's thickness: the gap on a smooth
plate); a Beverloo-like law says it is c·(gap − k·D): the powder flows through the gap less a
boundary band of k diameters, at packing c. Fitted by weighted least squares over the points
with gap ≥ MIN_GAP_D·D (2: where more than one layer fits), with 95 % intervals of c and k from
the fit's covariance (k by the delta method), and the fit's χ²/dof. Points below 1.8 D
on the smooth plate are judged against the monolayer's ceiling, a hexagonal layer π/(3√3)·D/gap = 0.6046·D/gap.
"""
import glob, json, math, os, sys

def points(runs):
    out = []
    for case in glob.glob(os.path.join(runs, "*")):
        f = os.path.join(case, "result.json")
        if not os.path.isdir(case) or not os.path.exists(f):
            continue
        r = json.load(open(f))
        p = r["parameters"]
        t = r["layer_thickness"] * 1e3
        substrate = os.path.basename(case).split("-")[0]
        out.append((substrate, p["diameter"], p["blade_speed"], p["gap"], r["layer_packing"], r["layer_packing_se"],
                    t, r["mfr"], r["mfr_se"], r.get("cpu_time") or float("nan")))
    return sorted(out)

def fit(xs, ys, ses):
    """Weighted least squares y = a·x + b: (a, b, cov(a, b), χ²/dof)."""
    w = [1 / s ** 2 for s in ses]
    sw = sum(w); sx = sum(wi * x for wi, x in zip(w, xs)); sy = sum(wi * y for wi, y in zip(w, ys))
    sxx = sum(wi * x * x for wi, x in zip(w, xs)); sxy = sum(wi * x * y for wi, x, y in zip(w, xs, ys))
    det = sw * sxx - sx * sx
    a = (sw * sxy - sx * sy) / det
    b = (sxx * sy - sx * sxy) / det
    chi2 = sum(wi * (y - a * x - b) ** 2 for wi, x, y in zip(w, xs, ys))
    dof = len(xs) - 2
    scale = max(1.0, chi2 / dof) if dof > 0 else 1.0   # widen by the scatter beyond the SEs
    cov = [[sw / det * scale, -sx / det * scale], [-sx / det * scale, sxx / det * scale]]
    return a, b, cov, chi2 / dof if dof > 0 else float("nan")

def main():
    runs = sys.argv[1]
    min_gap = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    pts = points(runs)
    ceiling = math.pi / (3 * math.sqrt(3))   # a hexagonal layer of spheres: 0.6046·D of solid per area
    print("| substrate | D mm | v m/s | gap mm | gap/D | MFR ± SE | layer mm | packing ± SE | packing·layer mm | monolayer ceiling | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for sub, d, v, g, phi, se, t, m, mse, cpu in pts:
        ceil = f"{ceiling * d / g:.3f} ({'under' if phi <= ceiling * d / g + 2 * se else 'OVER'})" if g < 1.8 * d and sub == "smooth" else "–"
        print(f"| {sub} | {d:g} | {v:g} | {g:g} | {g / d:.2f} | {m:.4f} ± {mse:.4f} | {t:.3f} | {phi:.4f} ± {se:.4f} | {phi * t:.4f} | {ceil} | {cpu:.0f} |")
    for sub, d, v in sorted({p[:3] for p in pts}):
        sel = [p for p in pts if p[:3] == (sub, d, v) and p[3] >= min_gap * d]
        if len(sel) < 3:
            continue
        xs = [p[6] for p in sel]                      # layer thickness, mm
        ys = [p[4] * p[6] for p in sel]               # packing × thickness, mm
        ses = [p[5] * p[6] for p in sel]
        a, b, cov, chi = fit(xs, ys, ses)
        k = -b / (a * d)
        # k = -b / (a·D): gradient (b/(a²D), -1/(aD))
        ga, gb = b / (a * a * d), -1 / (a * d)
        var_k = ga * ga * cov[0][0] + 2 * ga * gb * cov[0][1] + gb * gb * cov[1][1]
        z = 1.96
        print(f"\n{sub}, D {d:g} mm, {v:g} m/s, {len(sel)} points with gap ≥ {min_gap:g} D: packing·layer = c·(layer − k·D), "
              f"c = {a:.3f} ± {z * math.sqrt(cov[0][0]):.3f}, k = {k:.2f} ± {z * math.sqrt(var_k):.2f} (95 %), "
              f"χ²/dof {chi:.2f}")

if __name__ == "__main__":
    main()
