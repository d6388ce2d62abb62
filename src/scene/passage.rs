//! The screen's geometric criterion: whether nothing at all can pass under the blade's tip at a
//! point, so that its MFR is zero without a run (thesis Fig. 4.19: the closed gaps are real
//! zeros).
//!
//! Nothing passes when even the smallest particle, resting as low as it can and pressed down as
//! far as the blade's load can press it, stands taller than the gap. On a smooth plate the
//! lowest top of a sphere of diameter d is d. On the rough substrate (fixed spheres of radius R
//! on a square lattice of spacing s, tops at z = 0, centres at z = −R) a sphere of radius r
//! sits lowest on the axis of a pocket of four, where its centre is s/√2 across from each of
//! the four centres and R + r from them:
//!
//! ```text
//! z_top = −R + √((R + r)² − s²/2) + r        (d = D = s: D/√2 ≈ 0.707 D; s = 1.05 D: 0.670 D)
//! ```
//!
//! or on the plate below the substrate (z_lo + 2r) if it is small enough to drop through.
//!
//! The margin: contacts are soft (E = 21 MPa), so a sphere under the blade can sink into its
//! contacts. The deepest that load can press it is bounded by an elastic Hertz impact at the
//! blade speed, once against the blade and once against its support (fixed spheres or the
//! plate, so m* = m): δmax = (15 m v² / (16 Y* √R*))^(2/5) (Johnson §11.4; [`Pair`]). At
//! E = 21 MPa, ν = 0.3, ρ = 7980 kg/m³ and v = 1.6 m/s that is 0.069 D + 0.079 D = 0.147 D, the
//! same for every D (δ ∝ D). The steady push of the heap is far smaller: the whole heap's
//! friction (μ 0.3 × its weight, 0.25 N at D = 3 mm) on one sphere–blade contact sinks it by
//! 0.019 D. Impacts are damped (e < 1), so this margin over-states the sinking: the screen only
//! closes points that are clearly closed, and its verification sample checks it on the engine
//! ([`crate::run::screen`]).
//!
//! Not responsible for what the sweep does with a closed point (that is [`crate::run::screen`]).

use crate::contact::model::{effective_youngs, Material, Pair};

use super::Scene;

impl Scene {
    /// Height above the substrate's top (z = 0) of the top of the smallest particle resting as
    /// low as it can: in a pocket of four substrate spheres, on the plate under them if it drops
    /// through, or on the smooth plate. Metres.
    pub fn lowest_top(&self) -> f64 {
        let r = 0.5 * self.min_diameter();
        if self.substrate_particles == 0 {
            return 2.0 * r;
        }
        if let Some(bed) = &self.substrate_bed {
            return bed.lowest_top(2.0 * r);
        }
        let big_r = 0.5 * self.substrate_diameter;
        let s = self.substrate_spacing;
        // Squared distance from the pocket's axis to each of the four centres, horizontally.
        let across2 = 0.5 * s * s;
        let on_plate = self.z_lo + r;
        let in_pocket = if (big_r + r).powi(2) > across2 {
            -big_r + ((big_r + r).powi(2) - across2).sqrt()
        } else {
            f64::NEG_INFINITY
        };
        in_pocket.max(on_plate) + r
    }

    /// How far the blade's load can press the smallest resting particle down into its contacts:
    /// the Hertz overlap of a head-on elastic impact at the blade speed against the blade, plus
    /// the same against its support (a substrate sphere, or the plate). Metres.
    pub fn load_margin(&self) -> f64 {
        let r = 0.5 * self.min_diameter();
        let m = self.density * std::f64::consts::PI * (2.0 * r).powi(3) / 6.0;
        // The blade, plate and substrate are of the particles' material (the deck's types 2, 3).
        let material = Material { youngs: self.youngs_modulus, poisson: self.poisson };
        let pair = |r_eff: f64| Pair {
            y_eff: effective_youngs(material, material),
            g_eff: 0.0,
            beta: 0.0,
            friction: 0.0,
            r_eff,
            // Blade and substrate do not move under the impact.
            m_eff: m,
        };
        let support = if self.substrate_particles > 0 {
            let big_r = 0.5 * self.substrate_diameter;
            r * big_r / (r + big_r)
        } else {
            r
        };
        let v = self.blade_speed;
        pair(r).hertz_max_overlap(v) + pair(support).hertz_max_overlap(v)
    }

    /// Whether nothing can pass under the blade's tip: the gap is below the lowest top of the
    /// smallest particle less the load margin.
    pub fn nothing_passes(&self) -> bool {
        self.gap < self.lowest_top() - self.load_margin()
    }

    /// The smallest sphere of the powder, m.
    pub fn min_diameter(&self) -> f64 {
        self.size_classes.iter().map(|c| c.diameter).fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use crate::scene::settings::{SceneSettings, SizeDistributionSpec};

    use super::*;

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
        let mut s = scene(&[("diameter", 2.0)], &SceneSettings::default());
        s.substrate_spacing = s.diameter;
        assert!(close(s.lowest_top(), 2e-3 / 2f64.sqrt()), "{}", s.lowest_top());
    }

    #[test]
    fn the_default_substrate_spacing_lowers_it_to_0_670_d() {
        // Six diameters of depth hold 6 lattice spacings of 1.05 D, so s = 1.05 D:
        // √(1 − 1.05²/2) D = √0.44875 D = 0.669888 D.
        let s = scene(&[("diameter", 3.0)], &SceneSettings::default());
        assert!(close(s.substrate_spacing, 1.05 * 3e-3));
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
        assert!(close(s.substrate_spacing, 2.1e-3) && close(s.z_lo, -2e-3));
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
