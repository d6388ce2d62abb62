//! The report's pictures of a layers point: its answer pass by pass, and a top view of the layer
//! its last pass left (`dump.layer.K`, the particles over the plate after pass K).

use std::collections::HashSet;
use std::path::Path;

use super::measure::{layer_dump, read_grains};
use super::plan_of;
use super::result::LayerSeries;
use crate::scene::Scene;
use crate::scenes::figures::{Disc, PassSeries, TopView};

/// The series the steady layer was read from (packing on a fused bed, relative density on a
/// loose one), with each pass's covered fraction.
pub fn pass_series(l: &LayerSeries, fused: bool) -> PassSeries {
    let (mean, se) =
        if fused { (l.packing, l.packing_se) } else { (l.relative_density, l.relative_density_se) };
    PassSeries {
        passes: l
            .passes
            .iter()
            .map(|p| (p.k, if fused { p.packing } else { p.relative_density }, p.covered_fraction))
            .collect(),
        search_passes: l.passes.iter().filter(|p| p.search).count(),
        steady_from: l.steady_from,
        steady: (mean, se),
    }
}

/// The particles over the plate after pass `k`, seen from above. A loose bed's dump holds the
/// bed below too: those whose id the pass before already had are the bed (`height: None`); a
/// fused bed's dump holds only the pass's own. Heights are each top's about the median top of
/// the pass's own particles.
pub fn top_view(scene: &Scene, run_dir: &Path, k: usize) -> Result<TopView, String> {
    let plan = plan_of(scene);
    let grains = read_grains(&run_dir.join(layer_dump(k)))?;
    let before: HashSet<u64> = if plan.fused || k < 2 {
        HashSet::new()
    } else {
        read_grains(&run_dir.join(layer_dump(k - 1)))?.iter().map(|g| g.id).collect()
    };
    let mut tops: Vec<f64> = grains.iter().filter(|g| !before.contains(&g.id)).map(|g| g.z + g.r).collect();
    if tops.is_empty() {
        return Err(format!("pass {k} left no particle of its own over the plate"));
    }
    tops.sort_by(f64::total_cmp);
    let median = tops[tops.len() / 2];
    let mut discs: Vec<(f64, Disc)> = grains
        .iter()
        .map(|g| {
            let own = !before.contains(&g.id);
            (
                g.z + g.r,
                Disc {
                    x: g.x,
                    y: g.y.rem_euclid(scene.depth),
                    r: g.r,
                    height: own.then_some(g.z + g.r - median),
                },
            )
        })
        .collect();
    discs.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(TopView {
        pass: k,
        x: (plan.plate_x0, plan.plate_x1),
        y: (0.0, scene.depth),
        discs: discs.into_iter().map(|(_, d)| d).collect(),
    })
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::scenes::layers::settings::{with_own, LayersSettings};

    fn scene(bed: &str) -> Scene {
        let settings = with_own(LayersSettings::default().settings(), |l| {
            l.bed = bed.into();
            l.layers = 4;
        });
        let values: BTreeMap<String, f64> =
            [("diameter", 0.065), ("layer_thickness", 0.1), ("blade_speed", 0.1), ("density", 4386.0)]
                .iter()
                .map(|(k, v)| (k.to_string(), *v))
                .collect();
        crate::scenes::build(&values, &settings).unwrap()
    }

    /// A dump of spheres (id, x, y, z, radius), as the deck writes `dump.layer.K`.
    fn dump(dir: &Path, k: usize, grains: &[(u64, f64, f64, f64, f64)]) {
        let mut text = format!(
            "ITEM: TIMESTEP\n{k}\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS ff pp ff\n0 1\n0 1\n0 1\nITEM: ATOMS id x y z radius\n",
            grains.len()
        );
        for g in grains {
            text.push_str(&format!("{} {} {} {} {}\n", g.0, g.1, g.2, g.3, g.4));
        }
        std::fs::write(dir.join(layer_dump(k)), text).unwrap();
    }

    #[test]
    fn a_loose_beds_top_view_greys_the_bed_below_and_heights_the_new_particles_about_their_median() {
        let sc = scene("loose");
        let plan = plan_of(&sc);
        let dir = tempfile::tempdir().unwrap();
        let (x, r) = (plan.plate_x0 + 1e-4, 3e-5);
        // Pass 2 kept the bed's two particles (ids 1, 2) and laid three of its own, one across the
        // periodic face (y below 0).
        dump(dir.path(), 1, &[(1, x, 1e-5, 3e-5, r), (2, x, 5e-5, 3e-5, r)]);
        let pass2 = [
            (1, x, 1e-5, 3e-5, r),
            (2, x, 5e-5, 3e-5, r),
            (5, x, -1e-5, 1.0e-4, r),
            (3, x, 2e-5, 0.8e-4, r),
            (4, x, 3e-5, 1.3e-4, r),
        ];
        dump(dir.path(), 2, &pass2);
        let v = top_view(&sc, dir.path(), 2).unwrap();
        assert_eq!((v.pass, v.x, v.y), (2, (plan.plate_x0, plan.plate_x1), (0.0, sc.depth)));
        // Lowest top first; the bed's two without a height; the new ones about the median top
        // (1.0e-4 + r).
        let heights: Vec<Option<f64>> = v.discs.iter().map(|d| d.height).collect();
        assert_eq!(heights.len(), 5);
        assert_eq!(&heights[..2], [None, None]);
        for (h, want) in heights[2..].iter().zip([-0.2e-4, 0.0, 0.3e-4]) {
            assert!((h.unwrap() - want).abs() < 1e-12, "{heights:?}");
        }
        // The one below the periodic face is drawn at its image inside the box.
        assert!(v.discs.iter().all(|d| (0.0..sc.depth).contains(&d.y)));
        assert!(v.discs.iter().any(|d| (d.y - (sc.depth - 1e-5)).abs() < 1e-12));
    }

    #[test]
    fn a_fused_beds_top_view_holds_only_its_passs_particles_whatever_their_ids() {
        let sc = scene("fused");
        let plan = plan_of(&sc);
        let dir = tempfile::tempdir().unwrap();
        let x = plan.plate_x0 + 1e-4;
        // A fused deck renumbers: pass 2's particles may carry pass 1's ids.
        dump(dir.path(), 1, &[(1, x, 1e-5, 3e-5, 3e-5)]);
        dump(dir.path(), 2, &[(1, x, 1e-5, 4e-5, 3e-5), (2, x, 4e-5, 6e-5, 3e-5)]);
        let v = top_view(&sc, dir.path(), 2).unwrap();
        assert!(v.discs.iter().all(|d| d.height.is_some()), "{v:?}");
        // No pass of its own over the plate: said, not drawn.
        dump(dir.path(), 3, &[]);
        assert!(top_view(&sc, dir.path(), 3).unwrap_err().contains("pass 3 left no particle"));
    }
}
