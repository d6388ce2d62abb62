//! One snapshot of a dump as the measurements read it.

use crate::engine::dump::{DumpError, Snapshot};

/// The columns the metrics need (the deck dumps these and `y`, which the layer's coverage and
/// roughness read when it is there).
pub const COLUMNS: [&str; 5] = ["id", "x", "z", "vx", "mass"];

/// The particle data of one snapshot that the metrics read.
#[derive(Debug, Clone, Default)]
pub struct Frame {
    pub step: u64,
    pub id: Vec<u64>,
    pub x: Vec<f64>,
    /// Across the blade: read when the dump has it (the layer's coverage and roughness).
    pub y: Option<Vec<f64>>,
    pub z: Vec<f64>,
    pub vx: Vec<f64>,
    pub mass: Vec<f64>,
}

impl Frame {
    pub fn from_snapshot(s: &Snapshot) -> Result<Frame, DumpError> {
        let col = |name: &str| s.column(name).expect("columns were required when reading");
        let (id, x, z, vx, mass) = (col("id"), col("x"), col("z"), col("vx"), col("mass"));
        Ok(Frame {
            step: s.timestep,
            id: s.column_values(id).map(|v| v as u64).collect(),
            x: s.column_values(x).collect(),
            y: s.column("y").map(|c| s.column_values(c).collect()),
            z: s.column_values(z).collect(),
            vx: s.column_values(vx).collect(),
            mass: s.column_values(mass).collect(),
        })
    }

    pub fn len(&self) -> usize {
        self.id.len()
    }

    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }
}
