//! The Halton sequence: radical inverses in the first primes, plain or scrambled.
//!
//! Placeholder: plain Halton only; scrambling lands with the design work.

use crate::sweep::Scrambling;

/// The first primes, one base per dimension.
pub fn primes(count: usize) -> Vec<u64> {
    let mut out = Vec::with_capacity(count);
    let mut candidate = 2u64;
    while out.len() < count {
        if out.iter().take_while(|&&p| p * p <= candidate).all(|&p| candidate % p != 0) {
            out.push(candidate);
        }
        candidate += 1;
    }
    out
}

/// Radical inverse of `index` in `base`: the digits of `index` mirrored about the radix point.
pub fn radical_inverse(mut index: u64, base: u64) -> f64 {
    let inv = 1.0 / base as f64;
    let mut factor = inv;
    let mut value = 0.0;
    while index > 0 {
        value += (index % base) as f64 * factor;
        index /= base;
        factor *= inv;
    }
    value
}

/// The first `n` points of the `dim`-dimensional Halton sequence, skipping index 0 (the origin).
pub fn halton(dim: usize, n: usize, scrambling: Scrambling, seed: u64) -> super::Points {
    let _ = (scrambling, seed);
    let bases = primes(dim);
    (1..=n as u64).map(|i| bases.iter().map(|&b| radical_inverse(i, b)).collect()).collect()
}
