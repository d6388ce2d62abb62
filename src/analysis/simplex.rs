//! Nelder–Mead minimisation of a function of a few variables without derivatives: the
//! emulator's likelihood, the size-distribution fit.

/// Nelder–Mead minimisation of `f` from `start` (steps of `step` in every coordinate), at most
/// `iters` iterations; `project` moves every trial point back into the domain.
pub fn minimise(
    f: &dyn Fn(&[f64]) -> f64,
    start: &[f64],
    step: f64,
    iters: usize,
    project: &dyn Fn(&mut [f64]),
) -> Vec<f64> {
    let m = start.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = (0..=m)
        .map(|i| {
            let mut p = start.to_vec();
            if i > 0 {
                p[i - 1] += step;
            }
            project(&mut p);
            let v = f(&p);
            (p, v)
        })
        .collect();
    for _ in 0..iters {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        if (simplex[m].1 - simplex[0].1).abs() < 1e-6 {
            break;
        }
        let centroid: Vec<f64> =
            (0..m).map(|j| simplex[..m].iter().map(|s| s.0[j]).sum::<f64>() / m as f64).collect();
        let along = |t: f64| {
            let mut p: Vec<f64> = centroid.iter().zip(&simplex[m].0).map(|(c, w)| c + t * (c - w)).collect();
            project(&mut p);
            let v = f(&p);
            (p, v)
        };
        let r = along(1.0);
        if r.1 < simplex[0].1 {
            let e = along(2.0);
            simplex[m] = if e.1 < r.1 { e } else { r };
        } else if r.1 < simplex[m - 1].1 {
            simplex[m] = r;
        } else {
            let c = along(-0.5);
            if c.1 < simplex[m].1 {
                simplex[m] = c;
            } else {
                let best = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    let mut p: Vec<f64> = best.iter().zip(&s.0).map(|(b, q)| b + 0.5 * (q - b)).collect();
                    project(&mut p);
                    let v = f(&p);
                    *s = (p, v);
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    simplex.swap_remove(0).0
}
