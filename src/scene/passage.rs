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
        let Some(sub) = self.substrate().filter(|s| s.substrate_particles > 0) else {
            return 2.0 * r;
        };
        if let Some(bed) = &sub.substrate_bed {
            return bed.lowest_top(2.0 * r);
        }
        let big_r = 0.5 * sub.substrate_diameter;
        let s = sub.substrate_spacing;
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
    /// the same against its support (a substrate sphere, or the plate). Metres; 0 without a
    /// blade.
    pub fn load_margin(&self) -> f64 {
        let Some(blade) = self.blade() else { return 0.0 };
        let r = 0.5 * self.min_diameter();
        let m = self.material.density * std::f64::consts::PI * (2.0 * r).powi(3) / 6.0;
        // The blade, plate and substrate are of the particles' material (the deck's types 2, 3).
        let material = Material { youngs: self.material.youngs_modulus, poisson: self.material.poisson };
        let pair = |r_eff: f64| Pair {
            y_eff: effective_youngs(material, material),
            g_eff: 0.0,
            beta: 0.0,
            friction: 0.0,
            r_eff,
            // Blade and substrate do not move under the impact.
            m_eff: m,
        };
        let support = if let Some(sub) = self.substrate().filter(|s| s.substrate_particles > 0) {
            let big_r = 0.5 * sub.substrate_diameter;
            r * big_r / (r + big_r)
        } else {
            r
        };
        let v = blade.blade_speed;
        pair(r).hertz_max_overlap(v) + pair(support).hertz_max_overlap(v)
    }

    /// Whether nothing can pass under the blade's tip: the gap is below the lowest top of the
    /// smallest particle less the load margin. Always false without a blade.
    pub fn nothing_passes(&self) -> bool {
        self.blade().is_some_and(|b| b.gap < self.lowest_top() - self.load_margin())
    }

    /// The smallest sphere of the powder, m.
    pub fn min_diameter(&self) -> f64 {
        self.size_classes.iter().map(|c| c.diameter).fold(f64::INFINITY, f64::min)
    }
}
