//! The inclusive lattice: n values per dimension spanning [0, 1], n^d points.

/// The lattice with `n` values per dimension in `dim` dimensions.
///
/// Callers check the size first with [`super::lattice_size`] (n ≥ 2, at most
/// [`super::MAX_POINTS`] points); the asserts here only guard against that being skipped.
///
/// Order is stable: the last dimension varies fastest (row-major, like nested loops over the
/// parameters in file order). Coordinates are k/(n−1), k = 0..n−1, so both ends are present.
pub fn lattice(dim: usize, n: usize) -> super::Points {
    assert!(n >= 2, "a lattice needs at least two values per dimension");
    let total = n.checked_pow(dim as u32).expect("lattice too large");
    let step = 1.0 / (n - 1) as f64;
    (0..total)
        .map(|mut index| {
            let mut point = vec![0.0; dim];
            for coord in point.iter_mut().rev() {
                let k = index % n;
                index /= n;
                *coord = if k == n - 1 { 1.0 } else { k as f64 * step };
            }
            point
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_n_to_the_d() {
        assert_eq!(lattice(4, 5).len(), 625);
        assert_eq!(lattice(4, 10).len(), 10_000);
        assert_eq!(lattice(1, 3), vec![vec![0.0], vec![0.5], vec![1.0]]);
    }

    #[test]
    fn both_ends_of_every_dimension_are_present() {
        let pts = lattice(4, 5);
        for d in 0..4 {
            assert!(pts.iter().any(|p| p[d] == 0.0));
            assert!(pts.iter().any(|p| p[d] == 1.0));
        }
        // First point is the origin corner, last the opposite corner.
        assert_eq!(pts[0], vec![0.0; 4]);
        assert_eq!(pts[624], vec![1.0; 4]);
    }

    #[test]
    fn points_are_distinct() {
        let mut pts: Vec<String> = lattice(3, 6).iter().map(|p| format!("{p:?}")).collect();
        pts.sort();
        pts.dedup();
        assert_eq!(pts.len(), 216);
    }
}
