//! Row-major f64 matrices as plain arrays (`m[row][column]`), so the reference reads like the
//! formulas in `splat/mod.rs`.

pub(super) type Mat3 = [[f64; 3]; 3];

/// `a · b`.
pub(super) fn mul<const R: usize, const K: usize, const C: usize>(
    a: &[[f64; K]; R],
    b: &[[f64; C]; K],
) -> [[f64; C]; R] {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..K).map(|k| a[r][k] * b[k][c]).sum()))
}

/// `aᵀ`.
pub(super) fn transpose<const R: usize, const C: usize>(a: &[[f64; C]; R]) -> [[f64; R]; C] {
    std::array::from_fn(|c| std::array::from_fn(|r| a[r][c]))
}

/// `a · v`.
pub(super) fn mul_vec<const R: usize, const C: usize>(a: &[[f64; C]; R], v: [f64; C]) -> [f64; R] {
    std::array::from_fn(|r| (0..C).map(|c| a[r][c] * v[c]).sum())
}

pub(super) fn dot<const N: usize>(a: [f64; N], b: [f64; N]) -> f64 {
    (0..N).map(|k| a[k] * b[k]).sum()
}
