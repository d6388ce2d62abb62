//! The shared parts of a scene — its pile, the passage under the blade, the flux metrics, the
//! layer's quality and the plausibility bounds — checked on scenes this layout builds. They sit
//! below the layouts (docs/architecture.md) and cannot build a scene themselves, so their tests
//! that need a whole scene live here.

mod pile {
    use std::collections::BTreeMap;

    use crate::scene::pile::pile_data;
    use crate::scene::settings::{SceneSettings, SizeDistributionSpec};

    fn atoms(data: &str) -> Vec<[f64; 7]> {
        let body = data.split("Atoms\n\n").nth(1).unwrap();
        body.lines()
            .map(|l| {
                let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
                [v[0], v[1], v[2], v[3], v[4], v[5], v[6]]
            })
            .collect()
    }

    #[test]
    fn the_pile_has_the_planned_count_no_overlaps_and_lies_inside_the_box() {
        let settings = SceneSettings {
            size_distribution: SizeDistributionSpec::Weibull { bins: 5 },
            ..SceneSettings::gated()
        };
        let s = crate::scenes::build(&BTreeMap::new(), &settings).unwrap();
        let a = atoms(&pile_data(&s));
        assert_eq!(a.len(), s.atoms());
        assert!(s.substrate().unwrap().substrate_particles > 0);
        for (n, p) in a.iter().enumerate() {
            assert_eq!(p[0] as usize, n + 1);
            let r = p[2] / 2.0;
            assert!(p[4] - r >= 0.0 && p[4] + r < s.x_hi);
            if n < s.particles {
                assert_eq!(p[1], 1.0);
                assert!(p[6] - r > 0.0 && p[6] + r < s.z_hi);
                assert!(
                    p[4] + r < crate::scenes::moving_blade::spread(&s).own.gate_x,
                    "the dose lies behind the gate"
                );
            } else {
                // The substrate: tops at z = 0, standing on the plate.
                assert_eq!(p[1], 3.0);
                assert!((p[6] + r).abs() < 1e-12 && (p[6] - r - s.z_lo).abs() < 1e-12);
            }
        }
        // No sphere of the dose overlaps another or the substrate (a brute-force sample).
        for i in (0..s.particles).step_by(7) {
            for j in 0..a.len() {
                if i == j {
                    continue;
                }
                let d2: f64 = (4..7).map(|k| (a[i][k] - a[j][k]).powi(2)).sum();
                let contact = (a[i][2] + a[j][2]) / 2.0;
                assert!(d2.sqrt() > contact, "atoms {} and {} overlap", i + 1, j + 1);
            }
        }
    }

    #[test]
    fn the_pile_is_reproducible_and_changes_with_the_seed() {
        let s = crate::scenes::build(&BTreeMap::new(), &SceneSettings::gated()).unwrap();
        assert_eq!(pile_data(&s), pile_data(&s));
        let other =
            crate::scenes::build(&BTreeMap::new(), &SceneSettings { seed: 7, ..SceneSettings::gated() })
                .unwrap();
        assert_ne!(pile_data(&s), pile_data(&other));
    }
}

mod passage {
    use std::collections::BTreeMap;

    use crate::scene::settings::{SceneSettings, SizeDistributionSpec};

    use crate::scene::Scene;

    fn scene(pairs: &[(&str, f64)], settings: &SceneSettings) -> Scene {
        let values: BTreeMap<String, f64> = pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        crate::scenes::build(&values, settings).unwrap()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * b.abs()
    }

    #[test]
    fn a_sphere_in_a_pocket_of_touching_spheres_stands_d_over_root_two() {
        // d = D = s: −D/2 + √(D² − D²/2) + D/2 = D/√2.
        let s = scene(&[("diameter", 2.0)], &SceneSettings::default());
        let d = s.diameter;
        let s = crate::scenes::conveyor::with_part(s, |p| p.spreader.substrate.substrate_spacing = d);
        assert!(close(s.lowest_top(), 2e-3 / 2f64.sqrt()), "{}", s.lowest_top());
    }

    #[test]
    fn the_default_substrate_spacing_lowers_it_to_0_670_d() {
        // Six diameters of depth hold 6 lattice spacings of 1.05 D, so s = 1.05 D:
        // √(1 − 1.05²/2) D = √0.44875 D = 0.669888 D.
        let s = scene(&[("diameter", 3.0)], &SceneSettings::default());
        assert!(close(s.substrate().unwrap().substrate_spacing, 1.05 * 3e-3));
        assert!(close(s.lowest_top(), 0.44875f64.sqrt() * 3e-3), "{}", s.lowest_top());
    }

    #[test]
    fn on_a_smooth_plate_the_lowest_top_is_the_smallest_diameter() {
        for layout in [("gated", "smooth"), ("thesis", "rough")] {
            let settings = SceneSettings {
                layout: layout.0.into(),
                substrate: layout.1.into(),
                ..SceneSettings::default()
            };
            assert!(close(scene(&[("diameter", 2.5)], &settings).lowest_top(), 2.5e-3));
        }
        // With classes, the smallest one: 0.5 × 2 mm.
        let settings = SceneSettings {
            layout: "thesis".into(),
            size_distribution: SizeDistributionSpec::Classes {
                classes: vec![[0.5, 0.3], [1.0, 0.4], [1.5, 0.3]],
                relative: true,
                basis: Default::default(),
            },
            ..SceneSettings::default()
        };
        assert!(close(scene(&[("diameter", 2.0)], &settings).lowest_top(), 1e-3));
    }

    #[test]
    fn a_sphere_small_enough_to_drop_through_a_pocket_rests_on_the_plate() {
        // R = 1 mm, s = 2.1 mm: the pocket's opening admits r < s/√2 − R = 0.4849 mm. A sphere of
        // r = 0.2 mm reaches the plate at z_lo = −2 mm: its top is at −1.6 mm.
        let mut s = scene(&[("diameter", 2.0)], &SceneSettings::default());
        s.size_classes = vec![crate::scene::psd::SizeClass { diameter: 0.4e-3, fraction: 1.0 }];
        assert!(close(s.substrate().unwrap().substrate_spacing, 2.1e-3) && close(s.z_lo, -2e-3));
        assert!(close(s.lowest_top(), -1.6e-3), "{}", s.lowest_top());
        // One just too large to drop through (r = 0.6 mm) sits in the pocket:
        // −1 + √(1.6² − 2.1²/2) + 0.6 = −0.4 + √0.355 mm.
        s.size_classes[0].diameter = 1.2e-3;
        assert!(close(s.lowest_top(), (-0.4 + 0.355f64.sqrt()) * 1e-3), "{}", s.lowest_top());
    }

    #[test]
    fn the_load_margin_is_two_hertz_impacts_at_the_blade_speed() {
        // D = 1 mm, ρ = 7980, E = 21 MPa, ν = 0.3, v = 1.6 m/s: m = 4.17831e-6 kg,
        // Y* = E/(2(1 − ν²)) = 11.5385 MPa. Against the blade R* = 0.5 mm:
        // (15 m v²/(16 Y* √R*))^0.4 = 6.85223e-5 m; against a substrate sphere R* = 0.25 mm:
        // 7.87115e-5 m. Together 0.147234 D, whatever D.
        for d in [1.0, 3.0] {
            let s = scene(&[("diameter", d), ("blade_speed", 1.6)], &SceneSettings::default());
            let want = (6.85223e-5 + 7.87115e-5) * d;
            assert!((s.load_margin() - want).abs() < 1e-5 * want, "{} vs {want}", s.load_margin());
        }
    }

    #[test]
    fn the_screen_closes_the_measured_zero_and_leaves_the_pockets_open() {
        // Measured: MFR = 0 at D 3 mm, gap 1 mm (0.33 D). At v = 1.4 m/s the margin is
        // 0.1472 × (1.4/1.6)^0.8 = 0.1323 D, so the screen closes gaps below 0.5376 D.
        let at =
            |gap: f64| scene(&[("diameter", 3.0), ("gap", gap), ("blade_speed", 1.4)], &Default::default());
        assert!(at(1.0).nothing_passes());
        assert!(at(0.53 * 3.0).nothing_passes());
        // Between the closing bound and the geometric 0.67 D, a sphere pressed into its pocket
        // could pass: the point runs. So do the pocket-filling gaps up to D and beyond.
        assert!(!at(0.545 * 3.0).nothing_passes());
        assert!(!at(0.8 * 3.0).nothing_passes());
        assert!(!at(3.0).nothing_passes());
    }
}

mod metrics {
    use std::collections::BTreeMap;

    use crate::measure::frame::Frame;
    use crate::measure::metrics::{self, MetricsError};
    use crate::scene::settings::SceneSettings;
    use crate::scene::Scene;

    fn scene() -> Scene {
        let values: BTreeMap<String, f64> = [("diameter", 2.0), ("gap", 4.0), ("blade_speed", 1.5)]
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect();
        crate::scenes::build(&values, &SceneSettings::gated()).unwrap()
    }

    fn window_steps(s: &Scene) -> Vec<u64> {
        let w = s.window().unwrap();
        let (t1, t2) = w.steps();
        (t1..=t2).step_by(w.dump_every as usize).collect()
    }

    /// The blade's rear and front faces at `step`.
    fn rear(s: &Scene, step: u64) -> f64 {
        s.blade().unwrap().rear_at(s.timestep, step)
    }

    fn front(s: &Scene, step: u64) -> f64 {
        s.blade().unwrap().front_at(s.timestep, step)
    }

    fn gap(s: &Scene) -> f64 {
        s.blade().unwrap().gap
    }

    /// The metrics of `frames` of `s`.
    fn compute(s: &Scene, frames: &[Frame]) -> Result<crate::measure::metrics::Metrics, MetricsError> {
        metrics::compute(s, s.blade().unwrap(), s.window().unwrap(), frames)
    }

    /// Particles at rest at height `z`, `per_length` kg per metre of x, spread evenly over the
    /// whole travel of the blade, as seen at every snapshot of the window.
    fn resting_layer(s: &Scene, per_length: f64, m: f64, z: f64) -> Vec<Frame> {
        let x_end = front(s, s.window().unwrap().spread_steps()) + s.diameter;
        let n = (per_length * x_end / m).round() as usize;
        let one = |step| Frame {
            step,
            id: (1..=n as u64).collect(),
            x: (0..n).map(|i| (i as f64 + 0.5) * x_end / n as f64).collect(),
            y: None,
            z: vec![z; n],
            vx: vec![0.0; n],
            mass: vec![m; n],
        };
        window_steps(s).into_iter().map(one).collect()
    }

    #[test]
    fn a_swept_layer_at_half_the_ideal_density_gives_mfr_one_half_on_both_faces() {
        // The blade sweeping over a resting layer sees exactly its mass pass under the tip:
        // MFR = λ / (ρ w h), on the rear and the front face alike.
        let s = scene();
        let ideal = s.material.density * s.depth * gap(&s);
        let m = compute(&s, &resting_layer(&s, 0.5 * ideal, 1e-7, gap(&s) / 2.0)).unwrap();
        assert!((m.mfr - 0.5).abs() < 0.01, "{}", m.mfr);
        assert!((m.mfr_flux - 0.5).abs() < 0.01, "{}", m.mfr_flux);
        assert!(m.steady);
        for w in &m.mfr_windows {
            assert!((w - 0.5).abs() < 0.03, "{w}");
        }
    }

    #[test]
    fn particles_above_the_tip_do_not_count() {
        // The same layer, but every particle above the tip (thrown over the blade).
        let s = scene();
        let ideal = s.material.density * s.depth * gap(&s);
        let m = compute(&s, &resting_layer(&s, 0.5 * ideal, 1e-7, gap(&s) * 1.01)).unwrap();
        assert_eq!(m.mfr, 0.0);
        assert_eq!(m.mfr_flux, 0.0);
    }

    #[test]
    fn a_particle_that_crosses_back_is_subtracted() {
        let s = scene();
        let steps = window_steps(&s);
        let (a, b, c) = (steps[0], steps[1], steps[2]);
        let frame = |step, x: f64| Frame {
            step,
            id: vec![7],
            x: vec![x],
            y: None,
            z: vec![0.0],
            vx: vec![0.0],
            mass: vec![1.0],
        };
        // Ahead of the rear face, then behind it, then ahead again: net zero.
        let mut frames =
            vec![frame(a, rear(&s, a) + 1e-4), frame(b, rear(&s, b) - 1e-4), frame(c, rear(&s, c) + 1e-4)];
        frames.extend(steps[3..].iter().map(|&t| frame(t, rear(&s, t) + 1e-4)));
        assert_eq!(compute(&s, &frames).unwrap().mfr, 0.0);
    }

    #[test]
    fn vx_layers_are_means_in_their_bands_and_empty_layers_are_none() {
        let s = scene();
        let steps = window_steps(&s);
        let t1 = steps[0];
        let x = front(&s, t1) + 2.0 * s.diameter;
        // Two particles in layer 1 (v = 1 and 2), one in layer 3 (v = 0.5), one too far ahead.
        let f = Frame {
            step: t1,
            id: vec![1, 2, 3, 4],
            x: vec![x, x, x, front(&s, t1) + 7.0 * s.diameter],
            y: None,
            z: vec![
                s.layer_height(1).unwrap(),
                s.layer_height(1).unwrap() + 0.9 * s.window().unwrap().vx_band,
                s.layer_height(3).unwrap(),
                s.layer_height(1).unwrap(),
            ],
            vx: vec![1.0, 2.0, 0.5, 9.0],
            mass: vec![1.0; 4],
        };
        let mut frames = vec![f];
        frames.extend(steps[1..].iter().map(|&step| Frame { step, ..Frame::default() }));
        let m = compute(&s, &frames).unwrap();
        assert_eq!(m.vx[0], Some(1.5));
        assert_eq!(m.vx[1], None);
        assert_eq!(m.vx[2], Some(0.5));
    }

    #[test]
    fn a_missing_snapshot_is_an_error() {
        let s = scene();
        let err = compute(&s, &[]).unwrap_err();
        assert_eq!(err, MetricsError::MissingSnapshot(s.window().unwrap().steps().0));
    }
}

mod layer {
    use std::collections::BTreeMap;

    use crate::measure::frame::Frame;
    use crate::measure::layer;
    use crate::scene::settings::SceneSettings;
    use crate::scene::Scene;

    /// The layer of `frame` under `s`'s blade.
    fn measure(s: &Scene, frame: &Frame, x0: f64, x1: f64) -> Option<crate::outcome::layer::Layer> {
        layer::measure(s, s.blade().unwrap().gap, frame, x0, x1)
    }

    /// A scene whose depth is exactly 6 D, so a square lattice of pitch D tiles it.
    fn scene() -> Scene {
        let values: BTreeMap<String, f64> =
            [("diameter", 2.0), ("gap", 4.0)].iter().map(|(k, v)| (k.to_string(), *v)).collect();
        let mut s = crate::scenes::build(&values, &SceneSettings::default()).unwrap();
        s.depth = 6.0 * s.diameter;
        s
    }

    /// Spheres of diameter D resting on z = 0 at the given (x, y) centres.
    fn frame(s: &Scene, xy: &[(f64, f64)]) -> Frame {
        let m = s.material.density * std::f64::consts::PI / 6.0 * s.diameter.powi(3);
        Frame {
            step: 0,
            id: (1..=xy.len() as u64).collect(),
            x: xy.iter().map(|p| p.0).collect(),
            y: Some(xy.iter().map(|p| p.1).collect()),
            z: vec![0.5 * s.diameter; xy.len()],
            vx: vec![0.0; xy.len()],
            mass: vec![m; xy.len()],
        }
    }

    #[test]
    fn a_square_monolayer_is_even_covers_pi_over_four_and_has_the_cap_roughness() {
        let s = scene();
        let d = s.diameter;
        // A strip of 38 D: 36 D measured (the last 2 D behind the blade left out), 12 bins of 3 D.
        let (x0, x1) = (0.0, 38.0 * d);
        let ny = (s.depth / d).round() as usize;
        // Touching spheres on a square lattice of pitch D over the measured 36 D.
        let xy: Vec<(f64, f64)> = (0..36)
            .flat_map(|i| (0..ny).map(move |j| ((i as f64 + 0.5) * d, (j as f64 + 0.5) * d)))
            .collect();
        let l = measure(&s, &frame(&s, &xy), x0, x1).unwrap();
        // Every bin holds 3·ny spheres: no variation at all.
        assert!(l.layer_cv < 1e-9, "{l:?}");
        assert_eq!(l.particles, 36 * ny);
        // Counting noise of n equal masses per bin: √(n m²)/(n m) = 1/√n, n = 3·ny.
        assert!((l.layer_cv_noise - 1.0 / (3.0 * ny as f64).sqrt()).abs() < 1e-12, "{l:?}");
        // Discs of diameter D on a pitch of D cover π/4 of the plane; on a D/4 grid the sampled
        // share is 12 of the 16 cell centres per D² (those within D/2 of the disc's centre).
        assert!((l.covered_fraction - 12.0 / 16.0).abs() < 1e-9, "{l:?}");
        // Heights: D/2 + √(r² − d²) at the 12 covered cell centres (d² = (k²+l²)(D/8)², k,l odd
        // in ±1, ±3), 0 at the 4 uncovered: the RMS about the mean, in D, worked out here.
        let r = 0.5;
        let hs: Vec<f64> = [1.0f64, 3.0]
            .iter()
            .flat_map(|&a| [1.0f64, 3.0].map(move |b| (a, b)))
            .map(|(a, b)| {
                let d2 = (a * a + b * b) / 64.0;
                if d2 < r * r {
                    0.5 + (r * r - d2).sqrt()
                } else {
                    0.0
                }
            })
            .collect();
        let mean = hs.iter().sum::<f64>() / 4.0;
        let rms = (hs.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / 4.0).sqrt();
        assert!((l.roughness_d - rms).abs() < 1e-9 && (l.height_d - mean).abs() < 1e-9, "{l:?} {rms} {mean}");
    }

    #[test]
    fn an_empty_half_shows_in_coverage_and_uniformity() {
        let s = scene();
        let d = s.diameter;
        let ny = (s.depth / d).round() as usize;
        // Spheres over the first half of a 38 D strip only (38 D measured of 40 D).
        let xy: Vec<(f64, f64)> = (0..19)
            .flat_map(|i| (0..ny).map(move |j| ((i as f64 + 0.5) * d, (j as f64 + 0.5) * d)))
            .collect();
        let l = measure(&s, &frame(&s, &xy), 0.0, 40.0 * d).unwrap();
        assert!((l.covered_fraction - 0.5 * 0.75).abs() < 0.02, "{l:?}");
        // Half the bins full and half empty: CV ≈ 1, far above the counting noise.
        assert!(l.layer_cv > 0.9 && l.layer_cv > 3.0 * l.layer_cv_noise, "{l:?}");
        // Nothing behind the blade: no layer, all zeros; a dump without y: no measure.
        let empty = measure(&s, &frame(&s, &[]), 0.0, 40.0 * d).unwrap();
        assert_eq!((empty.covered_fraction, empty.roughness_d, empty.particles), (0.0, 0.0, 0));
        let mut no_y = frame(&s, &xy);
        no_y.y = None;
        assert!(measure(&s, &no_y, 0.0, 40.0 * d).is_none());
    }
}

mod plausible {
    use crate::measure::plausible::check_squeezed;

    #[test]
    fn a_deposit_under_a_gap_no_sphere_fits_was_squeezed() {
        let scene_at = |gap: f64| {
            let values: std::collections::BTreeMap<String, f64> =
                [("diameter", 2.0), ("gap", gap)].iter().map(|(k, v)| (k.to_string(), *v)).collect();
            crate::scenes::build(&values, &Default::default()).unwrap()
        };
        // D 2 mm on the rough substrate: a sphere in a pocket stands 0.67 D = 1.34 mm tall.
        let closed = scene_at(1.2);
        let squeezed = |s: &crate::scene::Scene, mfr: f64| check_squeezed(s, s.blade().unwrap().gap, mfr);
        let err = squeezed(&closed, 0.39).unwrap_err().to_string();
        assert!(err.contains("0.60 D") && err.contains("0.67 D"), "{err}");
        assert!(squeezed(&closed, 0.0).is_ok());
        assert!(squeezed(&scene_at(1.5), 0.05).is_ok());
    }
}
