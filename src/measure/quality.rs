//! Spreading quality of one point from its v_x profile (thesis §4.1, Fig. 4.2).
//!
//! The thesis tells three kinds of profile apart by eye: *ideal* (v_x rising smoothly with
//! height: the bottom layers pass under the blade, the top ones ride with it), *inefficient*
//! (nearly uniform v_x: the pile moves with the blade instead of flowing through the gap) and
//! *unstable* (v_x fluctuating from layer to layer). Measured here on the profile u_k = v_k / v
//! (v the blade speed, k = 1..12 bottom to top, empty layers left out):
//!
//! - **jitter** J = RMS over interior layers of u_k − (u_{k−1} + u_{k+1})/2, the departure of
//!   each layer from its neighbours' mean (zero for any straight or gently curved profile);
//! - **rise** R = mean of the top three layers − mean of the bottom three.
//!
//! Unstable when J > [`UNSTABLE_JITTER`]; otherwise inefficient when R < [`IDEAL_RISE`];
//! otherwise ideal. Unknown with fewer than [`MIN_LAYERS`] filled layers or no blade speed.
//! The thresholds were read off LIGGGHTS profiles of `sweeps/quick.toml` on the scene before the
//! gated-dose rework (a smooth profile there had J ≈ 0.003 and R from 0.05 at gap 1.3 D to 0.1
//! at 2 D). On the gated scene v_x is within a few % of the blade speed in every layer, so its
//! points classify as inefficient (docs/statistics.md "Spreading quality").

use serde::Serialize;

/// Jitter (fraction of the blade speed) above which a profile is unstable.
pub const UNSTABLE_JITTER: f64 = 0.03;
/// Rise (fraction of the blade speed) below which a profile is inefficient.
pub const IDEAL_RISE: f64 = 0.06;
/// Filled layers needed to judge a profile.
pub const MIN_LAYERS: usize = 6;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    Ideal,
    Inefficient,
    Unstable,
    Unknown,
}

impl Quality {
    pub const ALL: [Quality; 4] = [Quality::Ideal, Quality::Inefficient, Quality::Unstable, Quality::Unknown];

    pub fn as_str(self) -> &'static str {
        match self {
            Quality::Ideal => "ideal",
            Quality::Inefficient => "inefficient",
            Quality::Unstable => "unstable",
            Quality::Unknown => "unknown",
        }
    }

    pub fn parse(s: &str) -> Option<Quality> {
        Quality::ALL.into_iter().find(|q| q.as_str() == s)
    }
}

/// The measures the class is decided on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Profile {
    pub jitter: f64,
    pub rise: f64,
}

/// Jitter and rise of a profile (m/s per layer, bottom to top) at blade speed `v` (m/s).
pub fn measure(vx: &[Option<f64>], v: f64) -> Option<Profile> {
    let u: Vec<f64> = vx.iter().flatten().map(|x| x / v).collect();
    if u.len() < MIN_LAYERS || !(v.is_finite() && v > 0.0) || u.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let dev: Vec<f64> = u.windows(3).map(|w| w[1] - 0.5 * (w[0] + w[2])).collect();
    let jitter = (dev.iter().map(|d| d * d).sum::<f64>() / dev.len() as f64).sqrt();
    let top = u[u.len() - 3..].iter().sum::<f64>() / 3.0;
    let bottom = u[..3].iter().sum::<f64>() / 3.0;
    Some(Profile { jitter, rise: top - bottom })
}

/// The class of a profile at blade speed `v`.
pub fn classify(vx: &[Option<f64>], v: f64) -> Quality {
    match measure(vx, v) {
        None => Quality::Unknown,
        Some(p) if p.jitter > UNSTABLE_JITTER => Quality::Unstable,
        Some(p) if p.rise < IDEAL_RISE => Quality::Inefficient,
        Some(_) => Quality::Ideal,
    }
}

/// The class of a finished run (its parameters hold the blade speed).
pub fn of_result(r: &crate::outcome::RunResult) -> Quality {
    classify(&r.vx, r.parameters.get("blade_speed").copied().unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn some(v: &[f64]) -> Vec<Option<f64>> {
        v.iter().copied().map(Some).collect()
    }

    #[test]
    fn liggghts_profiles_of_the_quick_sweep() {
        // `sweep run sweeps/quick.toml --set gap=G,blade_speed=1.4` (D = 1.5 mm), LIGGGHTS 3.8,
        // on the scene before the gated-dose rework.
        let gap3 =
            some(&[1.223, 1.240, 1.289, 1.315, 1.315, 1.342, 1.355, 1.364, 1.367, 1.367, 1.376, 1.380]);
        let gap2 =
            some(&[1.277, 1.298, 1.316, 1.325, 1.334, 1.346, 1.350, 1.353, 1.357, 1.360, 1.367, 1.372]);
        let p3 = measure(&gap3, 1.4).unwrap();
        // rise by hand: (1.367+1.376+1.380)/3 − (1.223+1.240+1.289)/3 = 1.37433 − 1.25067 = 0.12367 m/s
        assert!((p3.rise - 0.12367 / 1.4).abs() < 1e-4, "{p3:?}");
        assert!(p3.jitter < 0.01);
        assert_eq!(classify(&gap3, 1.4), Quality::Ideal);
        // gap = 1.33 D: (1.360+1.367+1.372)/3 − (1.277+1.298+1.316)/3 = 0.0693 m/s = 0.0495 v
        assert_eq!(classify(&gap2, 1.4), Quality::Inefficient);
    }

    #[test]
    fn gated_scene_profile_is_inefficient() {
        // The same command on the gated scene (gap 3 mm = 2 D): v_x ≈ v in every layer, falling
        // slightly with height. Rise by hand: top three (1.415+1.416+1.408)/3 = 1.41300, bottom
        // three (1.438+1.447+1.454)/3 = 1.44633.
        let gated =
            some(&[1.438, 1.447, 1.454, 1.446, 1.444, 1.437, 1.429, 1.427, 1.427, 1.415, 1.416, 1.408]);
        let p = measure(&gated, 1.4).unwrap();
        assert!((p.rise - (1.41300 - 1.446_333) / 1.4).abs() < 1e-5, "{p:?}");
        assert_eq!(classify(&gated, 1.4), Quality::Inefficient);
    }

    #[test]
    fn a_zigzag_is_unstable_and_a_flat_line_inefficient() {
        let zigzag: Vec<Option<f64>> = (0..12)
            .map(|k| Some(0.8 + 0.1 * k as f64 / 11.0 + if k % 2 == 0 { 0.08 } else { -0.08 }))
            .collect();
        // Each interior layer sits 0.16 from its neighbours' mean: J = 0.16 at v = 1.
        let p = measure(&zigzag, 1.0).unwrap();
        assert!((p.jitter - 0.16).abs() < 1e-12, "{p:?}");
        assert_eq!(classify(&zigzag, 1.0), Quality::Unstable);
        assert_eq!(classify(&some(&[1.3; 12]), 1.4), Quality::Inefficient);
    }

    #[test]
    fn too_few_layers_or_no_blade_speed_is_unknown() {
        let mut holes = some(&[1.0; 12]);
        for h in holes.iter_mut().skip(5) {
            *h = None;
        }
        assert_eq!(classify(&holes, 1.4), Quality::Unknown);
        assert_eq!(classify(&some(&[1.0; 12]), f64::NAN), Quality::Unknown);
        assert_eq!(classify(&some(&[1.0; 12]), 0.0), Quality::Unknown);
    }
}
