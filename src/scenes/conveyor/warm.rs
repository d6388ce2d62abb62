//! Warm starts: the powder a finished point left at and ahead of its blade (`dump.state`),
//! mapped onto another point of the same sweep, so that the new point starts from a flowing
//! heap instead of one built from rest.
//!
//! The map is a scaling: lengths by the ratio of the two powders' sizes (the substrate's lattice,
//! the blade and the heap's box all scale with D, so a heap resting in the old pockets rests in
//! the new ones), the periodic depth by the ratio of the two depths, velocities by the ratio of
//! the blade speeds (spins by that over the length ratio). Then whatever the new point's geometry
//! cannot hold goes: what overlaps the blade (another gap), the plate, the substrate or a sphere
//! already placed by more than [`OVERLAP_TOLERANCE`] of its diameter, what lies beyond the front
//! wall, and the top of a heap larger than the new point holds (its box is topped up by the deck
//! as usual when it is smaller). Two powders of another shape of size distribution do not map.

use std::path::Path;

use crate::engine::dump::read_dump;
use crate::scene::Scene;
use crate::scenes::ColdStart;

/// The end-of-run snapshot a warm start reads.
pub const STATE_DUMP: &str = "dump.state";
/// The mapped particles the warm-started deck reads (`read_data warm.data add`).
pub const WARM_DATA: &str = "warm.data";

/// The dump's columns, in the deck's order.
const STATE_COLUMNS: [&str; 12] =
    ["id", "x", "y", "z", "vx", "vy", "vz", "omegax", "omegay", "omegaz", "radius", "mass"];

/// The distance in the design's unit cube from which a warm start needs the whole cold warm-up:
/// over the first 24 points of the thesis space's LDS draw (neighbours a median 0.48 apart),
/// warm-ups of 0.03–0.1 s left MFR 3 ± 2 % high against long runs, some points by 4 SE, as the
/// heap of a neighbour that far off relaxes about as slowly as one from rest
/// (docs/study/warm-start). Nearer, the warm-up shrinks in proportion, down to
/// [`LEAST_WARMUP_SHARE`] of it.
pub const FULL_WARMUP_DISTANCE: f64 = 0.5;

/// The least share of the cold warm-up a warm start gets, however near its neighbour: in the
/// thesis space's 2,400-point LDS run both ways, warm starts 0.16–0.21 apart (a third to two
/// fifths of the cold warm-up) came out +4 ± 1 % above the same points from rest, those a
/// median 0.31 apart (three fifths) +0.1 ± 1.4 % (docs/study/thesis, `lds-2400-warm`): a
/// neighbour's heap starts the flow at once but still relaxes towards this point's.
pub const LEAST_WARMUP_SHARE: f64 = 0.6;

/// The largest overlap a mapped sphere may keep with its neighbours, in diameters: loaded
/// contacts in a heap overlap by a fraction of a percent; more is an artefact of the map.
const OVERLAP_TOLERANCE: f64 = 0.02;

/// A neighbour's state mapped onto a point: the scene to render and the data file it reads.
#[derive(Debug, Clone)]
pub struct Warm {
    pub scene: Scene,
    pub data: String,
    /// The name the deck reads `data` under, in its run directory.
    pub data_file: &'static str,
    pub particles: usize,
}

#[derive(Debug, Clone, Copy)]
struct Sphere {
    x: [f64; 3],
    r: f64,
    v: [f64; 6],
}

/// Map the state `from` left in `state` onto `to`, whose particle file is `to_pile` (its
/// substrate spheres, the ids the warm particles follow), `distance` apart in the design's unit
/// cube. `Err` says why the point starts cold.
pub fn map(from: &Scene, state: &Path, to: &Scene, to_pile: &str, distance: f64) -> Result<Warm, ColdStart> {
    let ratio = size_ratio(from, to)?;
    let snaps = read_dump(state, &STATE_COLUMNS)?;
    let snap = snaps.last().ok_or(ColdStart::EmptyDump)?;
    let col: Vec<_> = STATE_COLUMNS.iter().map(|c| snap.column(c).expect("required column")).collect();
    let (fb, tb) = (&super::part(from).spreader.blade, &super::part(to).spreader.blade);
    let (sy, sv) = (to.depth / from.depth, tb.blade_speed / fb.blade_speed);
    let c = super::held(to);
    let blade = ([tb.blade_x0, tb.blade_x0 + tb.blade_thickness], [tb.gap, tb.blade_top]);
    let mut mapped: Vec<Sphere> = (0..snap.len())
        .map(|i| {
            let g = |k: usize| snap.get(i, col[k]);
            Sphere {
                x: [
                    tb.blade_x0 + (g(1) - fb.blade_x0) * ratio,
                    (g(2) * sy).rem_euclid(to.depth),
                    g(3) * ratio,
                ],
                r: g(10) * ratio,
                v: [g(4) * sv, g(5) * sv, g(6) * sv, g(7) * sv / ratio, g(8) * sv / ratio, g(9) * sv / ratio],
            }
        })
        .filter(|p| {
            let [x, _, z] = p.x;
            x >= tb.blade_x0
                && x + p.r <= c.heap_x1
                && z - p.r >= to.z_lo
                && z + p.r <= to.z_hi
                && box_distance(x, z, blade) >= p.r
        })
        .collect();
    // Lowest first: the spheres that carry the heap are kept before those resting on them.
    mapped.sort_by(|a, b| a.x[2].total_cmp(&b.x[2]));
    let substrate = pile_spheres(to_pile);
    let mut kept =
        Grid::new(to.depth, 2.0 * mapped.iter().chain(&substrate).map(|p| p.r).fold(0.0, f64::max));
    for s in &substrate {
        kept.insert(*s);
    }
    let first_warm = kept.spheres.len();
    for p in mapped {
        if !kept.overlaps(&p) {
            kept.insert(p);
        }
    }
    let mut warm = kept.spheres.split_off(first_warm);
    // A heap larger than this point holds: its top goes (the deck tops a smaller one up).
    let front = tb.blade_x0 + tb.blade_thickness;
    let in_heap = |p: &Sphere| (front..=c.heap_x1).contains(&p.x[0]) && (0.0..=c.heap_z1).contains(&p.x[2]);
    // `warm` is sorted lowest first, so the heap's top is its last members.
    let excess = warm.iter().filter(|p| in_heap(p)).count().saturating_sub(c.heap_particles);
    let mut tops: Vec<usize> = (0..warm.len()).rev().filter(|&i| in_heap(&warm[i])).take(excess).collect();
    tops.sort_unstable();
    for i in tops.into_iter().rev() {
        warm.remove(i);
    }
    if warm.is_empty() {
        return Err(ColdStart::NothingFits);
    }
    let first_id = substrate.len() + 1;
    let data = data_file(&warm, first_id, to.material.density);
    Ok(Warm { scene: warm_started(to, distance), data, data_file: WARM_DATA, particles: warm.len() })
}

/// `to` started from a neighbour `distance` away: its warm-up shortened in proportion to the
/// distance (at least [`LEAST_WARMUP_SHARE`] of the cold one and the least warm warm-up), its
/// window as long.
pub fn warm_started(to: &Scene, distance: f64) -> Scene {
    let c = super::held(to);
    let window_blocks = c.max_blocks - c.warmup_blocks;
    let share = (distance / FULL_WARMUP_DISTANCE).clamp(LEAST_WARMUP_SHARE, 1.0);
    let warmup_blocks = ((c.warmup_blocks as f64 * share).ceil() as u64)
        .clamp(c.warm_warmup_blocks.min(c.warmup_blocks), c.warmup_blocks);
    let block_steps = c.block_steps;
    super::with_part(to.clone(), |p| {
        p.held.warm_start = true;
        p.held.warmup_blocks = warmup_blocks;
        p.held.max_blocks = warmup_blocks + window_blocks;
        p.spreader.window.window_length_steps = (warmup_blocks + window_blocks) * block_steps;
    })
}

/// The ratio of `to`'s sizes to `from`'s, the same for every class; an error for two powders of
/// another shape.
fn size_ratio(from: &Scene, to: &Scene) -> Result<f64, ColdStart> {
    let (a, b) = (&from.size_classes, &to.size_classes);
    let ratio = to.diameter / from.diameter;
    let same_shape = a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| {
            (q.diameter / p.diameter / ratio - 1.0).abs() < 1e-9 && (q.fraction - p.fraction).abs() < 1e-9
        });
    if !same_shape || !ratio.is_finite() || ratio <= 0.0 {
        return Err(ColdStart::OtherSizes);
    }
    Ok(ratio)
}

/// Distance in (x, z) from a point to the box `[x0, x1] × [z0, z1]` (0 inside).
fn box_distance(x: f64, z: f64, ([x0, x1], [z0, z1]): ([f64; 2], [f64; 2])) -> f64 {
    let dx = (x0 - x).max(x - x1).max(0.0);
    let dz = (z0 - z).max(z - z1).max(0.0);
    dx.hypot(dz)
}

/// The spheres of a LIGGGHTS data file's `Atoms` section (`id type diameter density x y z`).
fn pile_spheres(pile: &str) -> Vec<Sphere> {
    pile.lines()
        .skip_while(|l| l.trim() != "Atoms")
        .skip(1)
        .filter_map(|l| {
            let f: Vec<f64> = l.split_whitespace().filter_map(|t| t.parse().ok()).collect();
            (f.len() == 7).then(|| Sphere { x: [f[4], f[5], f[6]], r: 0.5 * f[2], v: [0.0; 6] })
        })
        .collect()
}

/// The warm particles as a data file for `read_data ... add`: ids after the substrate's, the
/// powder's type and this point's density, velocities and spins.
fn data_file(spheres: &[Sphere], first_id: usize, density: f64) -> String {
    use std::fmt::Write;
    let mut out = format!(
        "LIGGGHTS data file: demsweep warm start\n\n{} atoms\n3 atom types\n\nAtoms\n\n",
        spheres.len()
    );
    for (k, p) in spheres.iter().enumerate() {
        let _ = writeln!(
            out,
            "{} 1 {:.10e} {} {:.10e} {:.10e} {:.10e}",
            first_id + k,
            2.0 * p.r,
            density,
            p.x[0],
            p.x[1],
            p.x[2]
        );
    }
    out.push_str("\nVelocities\n\n");
    for (k, p) in spheres.iter().enumerate() {
        let v = p.v;
        let _ = writeln!(
            out,
            "{} {:.8e} {:.8e} {:.8e} {:.8e} {:.8e} {:.8e}",
            first_id + k,
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5]
        );
    }
    out
}

/// Spheres in cells of (x, z) columns, periodic across the depth, for the overlap check.
struct Grid {
    depth: f64,
    cell: f64,
    cells: std::collections::HashMap<(i64, i64, i64), Vec<usize>>,
    spheres: Vec<Sphere>,
}

impl Grid {
    fn new(depth: f64, cell: f64) -> Grid {
        Grid { depth, cell: cell.max(f64::MIN_POSITIVE), cells: Default::default(), spheres: Vec::new() }
    }

    fn key(&self, x: &[f64; 3]) -> (i64, i64, i64) {
        let k = |v: f64| (v / self.cell).floor() as i64;
        (k(x[0]), k(x[1]), k(x[2]))
    }

    fn insert(&mut self, s: Sphere) {
        let key = self.key(&s.x);
        self.cells.entry(key).or_default().push(self.spheres.len());
        self.spheres.push(s);
    }

    fn overlaps(&self, p: &Sphere) -> bool {
        let (i, j, k) = self.key(&p.x);
        let wrap = (self.depth / self.cell).ceil() as i64;
        for di in -1..=1 {
            for dk in -1..=1 {
                for dj in -1..=1 {
                    // Across the periodic depth the cells wrap (and every shift is looked at).
                    for shift in [0, wrap, -wrap] {
                        let Some(list) = self.cells.get(&(i + di, j + dj + shift, k + dk)) else { continue };
                        for &n in list {
                            let q = &self.spheres[n];
                            let mut dy = (p.x[1] - q.x[1]).abs();
                            dy = dy.min(self.depth - dy);
                            let dist =
                                ((p.x[0] - q.x[0]).powi(2) + dy * dy + (p.x[2] - q.x[2]).powi(2)).sqrt();
                            if p.r + q.r - dist > OVERLAP_TOLERANCE * 2.0 * p.r.min(q.r) {
                                return true;
                            }
                        }
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::super::held;
    use super::*;
    use std::collections::BTreeMap;

    use crate::scene::settings::SceneSettings;

    fn scene(pairs: &[(&str, f64)]) -> Scene {
        let values: BTreeMap<String, f64> = pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect();
        crate::scenes::build(&values, &SceneSettings::default()).unwrap()
    }

    /// A state dump of spheres on a square grid ahead of `s`'s blade, resting on its substrate.
    fn state_of(s: &Scene, dir: &Path, rows: usize) -> std::path::PathBuf {
        let d = s.diameter;
        let mut out =
            String::from("ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\nN\nITEM: BOX BOUNDS pp pp ff\n");
        out += &format!("0 {}\n0 {}\n{} {}\n", s.x_hi, s.depth, s.z_lo, s.z_hi);
        out += "ITEM: ATOMS id x y z vx vy vz omegax omegay omegaz radius mass\n";
        let mut n = 0;
        let per_y = (s.depth / (1.01 * d)).floor() as usize;
        for k in 0..rows {
            for i in 0..20 {
                for j in 0..per_y {
                    n += 1;
                    let b = &super::super::part(s).spreader.blade;
                    let x = b.blade_x0 + b.blade_thickness + (i as f64 + 0.5) * 1.01 * d;
                    let z = 0.67 * d + k as f64 * 1.01 * d;
                    out += &format!(
                        "{n} {x} {} {z} -0.5 0 0.1 0 20 0 {} 1e-5\n",
                        (j as f64 + 0.5) * 1.01 * d,
                        0.5 * d
                    );
                }
            }
        }
        let path = dir.join(STATE_DUMP);
        std::fs::write(&path, out.replace("\nN\n", &format!("\n{n}\n"))).unwrap();
        path
    }

    #[test]
    fn a_heap_maps_onto_a_larger_powder_at_scale_and_speed_with_no_overlap() {
        let dir = tempfile::tempdir().unwrap();
        let from = scene(&[("diameter", 1.0), ("gap", 3.0), ("blade_speed", 1.0)]);
        let to = scene(&[("diameter", 2.0), ("gap", 6.0), ("blade_speed", 1.5)]);
        let state = state_of(&from, dir.path(), 2);
        let pile = crate::scene::pile::pile_data(&to);
        let w = map(&from, &state, &to, &pile, 0.01).unwrap();
        assert!(w.particles > 50, "{} particles", w.particles);
        // However near, a warm start keeps LEAST_WARMUP_SHARE of the cold warm-up.
        let least = ((held(&to).warmup_blocks as f64 * LEAST_WARMUP_SHARE).ceil() as u64)
            .max(held(&to).warm_warmup_blocks.min(held(&to).warmup_blocks));
        assert!(held(&w.scene).warm_start && held(&w.scene).warmup_blocks == least);
        assert!(least < held(&to).warmup_blocks);
        assert_eq!(
            held(&w.scene).max_blocks - held(&w.scene).warmup_blocks,
            held(&to).max_blocks - held(&to).warmup_blocks
        );
        // The warm-up shrinks with the distance: the whole cold one from FULL_WARMUP_DISTANCE on.
        let far = map(&from, &state, &to, &pile, FULL_WARMUP_DISTANCE).unwrap();
        assert_eq!(held(&far.scene).warmup_blocks, held(&to).warmup_blocks);
        let most = map(&from, &state, &to, &pile, 0.8 * FULL_WARMUP_DISTANCE).unwrap();
        assert_eq!(held(&most.scene).warmup_blocks, (held(&to).warmup_blocks as f64 * 0.8).ceil() as u64);
        let atoms: Vec<Vec<f64>> = w
            .data
            .lines()
            .skip_while(|l| *l != "Atoms")
            .skip(2)
            .take_while(|l| !l.is_empty())
            .map(|l| l.split_whitespace().map(|t| t.parse().unwrap()).collect())
            .collect();
        assert_eq!(atoms.len(), w.particles);
        // Ids follow the substrate's; sizes doubled; heights doubled; velocities × 1.5.
        assert_eq!(atoms[0][0] as usize, to.substrate().unwrap().substrate_particles + 1);
        assert!(atoms.iter().all(|a| (a[2] - 2e-3).abs() < 1e-12));
        assert!(atoms.iter().all(|a| a[6] >= 0.67 * 2e-3 - 1e-9));
        let vel = w.data.lines().skip_while(|l| *l != "Velocities").nth(2).unwrap();
        let v: Vec<f64> = vel.split_whitespace().map(|t| t.parse().unwrap()).collect();
        assert!((v[1] + 0.75).abs() < 1e-9 && (v[5] - 20.0 * 1.5 / 2.0).abs() < 1e-9, "{vel}");
    }

    #[test]
    fn what_the_new_geometry_cannot_hold_goes() {
        let dir = tempfile::tempdir().unwrap();
        // A tall heap of small spheres onto a point whose heap is smaller and whose blade comes
        // down to a lower gap: nothing may overlap the blade, and the heap is trimmed to its count.
        let from = scene(&[("diameter", 1.0), ("gap", 4.0), ("blade_speed", 1.0)]);
        let to = scene(&[("diameter", 1.0), ("gap", 1.5), ("blade_speed", 1.0), ("heap_height", 5.0)]);
        let state = state_of(&from, dir.path(), 12);
        let pile = crate::scene::pile::pile_data(&to);
        let w = map(&from, &state, &to, &pile, 0.3).unwrap();
        assert!(w.particles <= held(&to).heap_particles + 200, "{}", w.particles);
        for l in w.data.lines().skip_while(|l| *l != "Atoms").skip(2).take_while(|l| !l.is_empty()) {
            let a: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            let (x, z, r) = (a[4], a[6], 0.5 * a[2]);
            let b = &super::super::part(&to).spreader.blade;
            let blade = ([b.blade_x0, b.blade_x0 + b.blade_thickness], [b.gap, b.blade_top]);
            assert!(box_distance(x, z, blade) >= r, "a sphere at x {x} z {z} overlaps the blade");
            assert!(x + r <= held(&to).heap_x1);
        }
    }

    #[test]
    fn another_size_distribution_starts_cold() {
        let dir = tempfile::tempdir().unwrap();
        let from = scene(&[("diameter", 1.0)]);
        let state = state_of(&from, dir.path(), 1);
        let weibull = SceneSettings {
            size_distribution: crate::scene::settings::SizeDistributionSpec::Weibull { bins: 5 },
            ..SceneSettings::default()
        };
        let values: BTreeMap<String, f64> = [("diameter".to_string(), 1.0)].into();
        let to = crate::scenes::build(&values, &weibull).unwrap();
        let err = map(&from, &state, &to, &crate::scene::pile::pile_data(&to), 0.1).unwrap_err().to_string();
        assert!(err.contains("size distribution"), "{err}");
    }
}
