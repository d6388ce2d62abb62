//! The Cholesky factor of a covariance matrix, and the triangular solve with many right-hand
//! sides, in blocks.
//!
//! Why not `nalgebra::Cholesky::new` alone: it factors column by column with vector updates, at
//! about the speed of memory, and a report's emulator factors matrices of a few thousand rows
//! (every run of a large sweep; the posterior covariance of the sample paths on 2,048 points).
//! Here the diagonal blocks are nalgebra's factor and everything else is matrix products
//! (`gemm`, which nalgebra hands to `matrixmultiply`'s cache-blocked kernels): the classic
//! right-looking blocked algorithm (Golub & Van Loan, Matrix Computations, 4th ed., §4.2.9).

use nalgebra::{Cholesky, DMatrix, Dyn};

/// Columns per block: large enough for the products to run at their kernels' speed, small enough
/// that the vector-speed work (the diagonal blocks and the panels' triangular solves) stays a
/// small share.
const BLOCK: usize = 48;

/// The Cholesky factor of `k` (its lower triangle read); `None` when `k` is not positive
/// definite or its factor not finite.
pub fn factor(k: DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    let n = k.nrows();
    let mut a = k;
    let mut j = 0;
    while j < n {
        let b = BLOCK.min(n - j);
        // The diagonal block: A11 = L11·L11ᵀ.
        let l11 = Cholesky::new(a.view((j, j), (b, b)).clone_owned())?.unpack();
        if !l11.diagonal().iter().all(|d| d.is_finite()) {
            return None;
        }
        a.view_mut((j, j), (b, b)).copy_from(&l11);
        let rest = n - j - b;
        if rest > 0 {
            // The panel: L21 = A21·L11⁻ᵀ, solved as L11·L21ᵀ = A21ᵀ.
            let mut l21t = a.view((j + b, j), (rest, b)).transpose();
            if !l11.solve_lower_triangular_mut(&mut l21t) {
                return None;
            }
            let l21 = l21t.transpose();
            a.view_mut((j + b, j), (rest, b)).copy_from(&l21);
            // The trailing matrix's lower triangle: A22 −= L21·L21ᵀ, one block column at a time
            // (the upper triangle is never read).
            let mut c = 0;
            while c < rest {
                let w = BLOCK.min(rest - c);
                let mut a22 = a.view_mut((j + b + c, j + b + c), (rest - c, w));
                a22.gemm(-1.0, &l21.rows(c, rest - c), &l21t.columns(c, w), 1.0);
                c += w;
            }
        }
        j += b;
    }
    // The strict upper triangle still holds the input: nalgebra reads only the lower one
    // (`l_dirty`), and `unpack`/`l` zero the rest.
    Some(Cholesky::pack_dirty(a))
}

/// Solve L·X = B in place for a lower-triangular `l` (its strict upper triangle not read) and a
/// matrix `b` of many columns, by block rows: each block row's update from the rows solved
/// before it is one matrix product, its diagonal block a small triangular solve. nalgebra's
/// own solve takes the columns one by one with vector updates.
pub fn solve_lower(l: &DMatrix<f64>, b: &mut DMatrix<f64>) {
    let n = l.nrows();
    let m = b.ncols();
    let mut r = 0;
    while r < n {
        let h = BLOCK.min(n - r);
        if r > 0 {
            let (done, mut rest) = b.rows_range_pair_mut(..r, r..);
            rest.rows_mut(0, h).gemm(-1.0, &l.view((r, 0), (h, r)), &done, 1.0);
        }
        l.view((r, r), (h, h)).solve_lower_triangular_unchecked_mut(&mut b.view_mut((r, 0), (h, m)));
        r += h;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A covariance matrix of `n` points on a line (squared-exponential, length `len`, a small
    /// nugget): well conditioned for long-range `len` only through its nugget.
    fn covariance(n: usize, len: f64, nugget: f64) -> DMatrix<f64> {
        DMatrix::from_fn(n, n, |i, j| {
            let r = (i as f64 - j as f64) / n as f64 / len;
            (-0.5 * r * r).exp() + if i == j { nugget } else { 0.0 }
        })
    }

    #[test]
    fn the_blocked_factor_is_the_unblocked_one_to_rounding() {
        // Sizes below, at and across block boundaries, one not a multiple of the block.
        for n in [5, 2 * BLOCK, 2 * BLOCK + 1, 3 * BLOCK + 17, 700] {
            let k = covariance(n, 0.2, 1e-3);
            let blocked = factor(k.clone()).unwrap().l();
            let plain = Cholesky::new(k.clone()).unwrap().l();
            let worst = (&blocked - &plain).abs().max();
            assert!(worst < 1e-10, "n {n}: largest difference {worst:e}");
            // And it is a factor: L·Lᵀ = K.
            let back = (&blocked * blocked.transpose() - &k).abs().max();
            assert!(back < 1e-12, "n {n}: |L·Lᵀ − K| {back:e}");
        }
    }

    #[test]
    fn the_solve_in_block_rows_is_nalgebra_s_to_rounding() {
        for n in [7, BLOCK, 3 * BLOCK + 17] {
            let l = factor(covariance(n, 0.2, 1e-2)).unwrap().l();
            // The strict upper triangle holds junk, as a factor's `l_dirty` may: never read.
            let mut dirty = l.clone();
            for j in 1..n {
                for i in 0..j {
                    dirty[(i, j)] = 1e3 + (i * j) as f64;
                }
            }
            let b = DMatrix::from_fn(n, 40, |i, j| ((i * 7 + j * 13) % 11) as f64 - 5.0);
            let mut ours = b.clone();
            solve_lower(&dirty, &mut ours);
            let theirs = l.solve_lower_triangular(&b).unwrap();
            let scale = theirs.abs().max();
            let worst = (&ours - &theirs).abs().max();
            assert!(worst <= 1e-10 * scale, "n {n}: largest difference {worst:e} of {scale:e}");
        }
    }

    #[test]
    fn a_matrix_not_positive_definite_past_the_first_block_has_no_factor() {
        // Positive definite in its first blocks, not in the last: the failure is found there.
        let n = 3 * BLOCK + 5;
        let mut k = covariance(n, 0.05, 1e-2);
        k[(n - 1, n - 1)] = -1.0;
        assert!(factor(k.clone()).is_none());
        k[(n - 1, n - 1)] = f64::NAN;
        assert!(factor(k).is_none());
    }
}
