//! Real spherical harmonics up to degree 3 with the constants and signs of the 3DGS
//! reference: the basis values at a direction and their derivatives with respect to its
//! components (the basis taken as polynomials in x, y, z; callers chain the normalisation).

const C0: f64 = 0.28209479177387814;
const C1: f64 = 0.4886025119029199;
const C2: [f64; 5] = [
    1.0925484305920792,
    -1.0925484305920792,
    0.31539156525252005,
    -1.0925484305920792,
    0.5462742152960396,
];
const C3: [f64; 7] = [
    -0.5900435899266435,
    2.890611442640554,
    -0.4570457994644658,
    0.3731763325901154,
    -0.4570457994644658,
    1.445305721320277,
    -0.5900435899266435,
];

/// The 16 basis values at `d` in coefficient order (DC first).
pub(super) fn basis(d: [f64; 3]) -> [f64; 16] {
    let [x, y, z] = d;
    let (xx, yy, zz) = (x * x, y * y, z * z);
    [
        C0,
        -C1 * y,
        C1 * z,
        -C1 * x,
        C2[0] * x * y,
        C2[1] * y * z,
        C2[2] * (2.0 * zz - xx - yy),
        C2[3] * x * z,
        C2[4] * (xx - yy),
        C3[0] * y * (3.0 * xx - yy),
        C3[1] * x * y * z,
        C3[2] * y * (4.0 * zz - xx - yy),
        C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy),
        C3[4] * x * (4.0 * zz - xx - yy),
        C3[5] * z * (xx - yy),
        C3[6] * x * (xx - 3.0 * yy),
    ]
}

/// `∂ basis_k / ∂(x, y, z)` at `d`, for every k.
pub(super) fn basis_gradient(d: [f64; 3]) -> [[f64; 3]; 16] {
    let [x, y, z] = d;
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let scaled = |c: f64, g: [f64; 3]| g.map(|v| c * v);
    [
        [0.0; 3],
        [0.0, -C1, 0.0],
        [0.0, 0.0, C1],
        [-C1, 0.0, 0.0],
        scaled(C2[0], [y, x, 0.0]),
        scaled(C2[1], [0.0, z, y]),
        scaled(C2[2], [-2.0 * x, -2.0 * y, 4.0 * z]),
        scaled(C2[3], [z, 0.0, x]),
        scaled(C2[4], [2.0 * x, -2.0 * y, 0.0]),
        scaled(C3[0], [6.0 * x * y, 3.0 * xx - 3.0 * yy, 0.0]),
        scaled(C3[1], [y * z, x * z, x * y]),
        scaled(C3[2], [-2.0 * x * y, 4.0 * zz - xx - 3.0 * yy, 8.0 * y * z]),
        scaled(C3[3], [-6.0 * x * z, -6.0 * y * z, 6.0 * zz - 3.0 * xx - 3.0 * yy]),
        scaled(C3[4], [4.0 * zz - 3.0 * xx - yy, -2.0 * x * y, 8.0 * x * z]),
        scaled(C3[5], [2.0 * x * z, -2.0 * y * z, xx - yy]),
        scaled(C3[6], [3.0 * xx - 3.0 * yy, -6.0 * x * y, 0.0]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn directions() -> Vec<[f64; 3]> {
        let mut rng = crate::rng::SplitMix64::new(11);
        (0..50)
            .map(|_| {
                let v = [0; 3].map(|_| rng.next_f64() * 2.0 - 1.0);
                let n = v.iter().map(|c| c * c).sum::<f64>().sqrt();
                v.map(|c| c / n)
            })
            .collect()
    }

    /// Addition theorem: within band l, Σ_m Y_lm(d)² = (2l + 1) / 4π at every unit d. This
    /// pins every constant and polynomial up to the sign of each basis function.
    #[test]
    fn bands_satisfy_the_addition_theorem() {
        for d in directions() {
            let b = basis(d);
            for l in 0..4usize {
                let band: f64 = b[l * l..(l + 1) * (l + 1)].iter().map(|v| v * v).sum();
                let expected = (2 * l + 1) as f64 / (4.0 * std::f64::consts::PI);
                assert!((band - expected).abs() < 1e-12, "band {l} at {d:?}: {band} vs {expected}");
            }
        }
    }

    #[test]
    fn gradient_matches_central_differences() {
        let h = 1e-6;
        for d in directions() {
            let g = basis_gradient(d);
            for axis in 0..3 {
                let (mut plus, mut minus) = (d, d);
                plus[axis] += h;
                minus[axis] -= h;
                let (bp, bm) = (basis(plus), basis(minus));
                for k in 0..16 {
                    let fd = (bp[k] - bm[k]) / (2.0 * h);
                    assert!(
                        (fd - g[k][axis]).abs() < 1e-8,
                        "k {k} axis {axis}: {fd} vs {}",
                        g[k][axis]
                    );
                }
            }
        }
    }
}
