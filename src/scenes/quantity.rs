//! The quantities of a result that `sweep calibrate --target NAME=…` can fit a sweep to. Each
//! layout names those its runs measure ([`super::Layout::calibration_targets`]): a flow under a
//! blade its MFR ([`MFR`]), a pour its heap's angle and packing (`pour::CALIBRATION_TARGETS`), the
//! layers their steady layer's relative density and packing (`layers::CALIBRATION_TARGETS`).

use crate::outcome::{AnswerKind, RunResult};

/// A measured value and the run's SE of it, where it gives one.
pub type Measured = (f64, Option<f64>);

/// A quantity a run measures that a calibration can target.
pub struct Quantity {
    pub name: &'static str,
    pub unit: &'static str,
    /// Its value in a result, with the result's SE of it where it gives one.
    pub read: fn(&RunResult) -> Option<Measured>,
    /// Runs of each setting by default (`--repeats`): 2 for a heap's quantities, whose own SE
    /// (over one heap's sectors) understates the scatter between seeds; 1 for MFR, whose SE is
    /// over the window's batches.
    pub repeats: usize,
    /// The values it can take: a target outside is a slip, and its SD is at most this width.
    pub possible: (f64, f64),
    /// Whether the lower end itself is a value it can take: MFR can be 0 (nothing passes), a
    /// heap's angle and packing cannot.
    pub lo_possible: bool,
}

impl Quantity {
    /// Its value in `r`, with the result's SE of it where it gives one.
    pub fn read(&self, r: &RunResult) -> Option<Measured> {
        (self.read)(r)
    }
}

/// The mass flow ratio of a flow under a blade, with its SE.
pub const MFR: Quantity = Quantity {
    name: "mfr",
    unit: "-",
    read: |r| {
        (r.answer.kind == AnswerKind::Mfr && r.answer.value.is_finite())
            .then_some((r.answer.value, r.answer.se))
    },
    repeats: 1,
    possible: (0.0, 1.0),
    lo_possible: true,
};

/// The quantity named `name`, of any layout.
pub fn lookup(name: &str) -> Option<&'static Quantity> {
    every().find(|q| q.name == name)
}

/// Every layout's quantities, each once, in registration order.
pub fn every() -> impl Iterator<Item = &'static Quantity> {
    let mut seen: Vec<&'static str> = Vec::new();
    super::LAYOUTS.iter().flat_map(|l| l.calibration_targets()).filter(move |q| {
        let new = !seen.contains(&q.name);
        seen.push(q.name);
        new
    })
}
