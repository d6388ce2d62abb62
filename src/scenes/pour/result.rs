//! The heap a pour leaves at rest: a pour's own result, `result.json`'s `heap` record
//! ([`super::heap`] measures it).

use serde::{Deserialize, Serialize};

use crate::outcome::own_result::LayoutResult;
use crate::outcome::RunResult;

/// The key of [`Heap`] in `result.json`.
pub const KEY: &str = "heap";

/// A pour's heap (`None` for a run of another layout, or a pour that left none).
pub fn heap(r: &RunResult) -> Option<&Heap> {
    r.own.get()
}

impl LayoutResult for Heap {
    fn key(&self) -> &'static str {
        KEY
    }
}

/// A heap's angle of repose, from a straight-line fit of its surface height against the radius
/// in each azimuthal sector, and its bulk packing.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Heap {
    /// Mean of the sectors' angles, degrees.
    pub angle_deg: f64,
    /// Standard error of `angle_deg` over the sectors (their standard deviation / √n), degrees.
    pub angle_se_deg: f64,
    /// The angle of each azimuthal sector, degrees, counter-clockwise from +x.
    pub sector_angles_deg: Vec<f64>,
    /// Height of the heap's top above the plate, mm.
    pub height_mm: f64,
    /// Radius of the fitted cone's foot on the plate (mean over the sectors), mm.
    pub base_radius_mm: f64,
    /// Solid fraction of the heap's core: the particles' volume over the volume of a cylinder
    /// under the surface, around the axis.
    pub packing: f64,
    /// Particles on the plate inside the heap, and those that ran out beyond its foot.
    pub particles_in_heap: usize,
    pub particles_run_out: usize,
}
