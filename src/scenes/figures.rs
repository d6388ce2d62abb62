//! What a layout that runs pass by pass gives the report to draw of one finished point: its
//! answer pass by pass, and a top view of the layer its last pass left.

/// A point's answer and covered fraction after each pass, and the steady layer read from them.
#[derive(Debug, Clone, PartialEq)]
pub struct PassSeries {
    /// (pass, the answer's measure after it, its covered fraction), from pass 1.
    pub passes: Vec<(usize, f64, f64)>,
    /// Passes that searched for a steady state rather than measuring it (drawn apart).
    pub search_passes: usize,
    /// The first pass of the steady layer, and its mean and SE.
    pub steady_from: usize,
    pub steady: (f64, f64),
}

/// One particle seen from above: its centre and radius over the plate (m), and its top's height
/// about the median of the layer's own particles (m; `None`: a particle of the bed below,
/// showing through where the layer left it bare).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    pub x: f64,
    pub y: f64,
    pub r: f64,
    pub height: Option<f64>,
}

/// A top view of the layer a pass left over the plate: its particles, lowest first, so that one
/// drawn later lies on top.
#[derive(Debug, Clone, PartialEq)]
pub struct TopView {
    /// The pass it shows.
    pub pass: usize,
    /// The plate's extent along the travel and across it, m.
    pub x: (f64, f64),
    pub y: (f64, f64),
    pub discs: Vec<Disc>,
}
